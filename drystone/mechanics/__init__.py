"""The mechanics (core layer): contact laws (``laws``, ``contact``), exact overlaps of
convex polyhedra (``overlap``), the compiled contact step (``contact_step``) and the
integration of rigid bodies (``integration``, ``rotations``), the checks that stop a run
(``stability``), the per-sample jobs of a run (``monitors``), collapse onsets
(``collapse``), modal analysis (``modal``) and closed forms (``analytic``). No YADE import."""
