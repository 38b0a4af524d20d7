"""The case model (core layer): case files and their keys (``keys``, ``case``), the stage
types (``stages``), the resolved run specification (``resolve``, ``spec``), the load
programme (``loading``) and the time step (``timestep``). No YADE import."""
