"""Where the compiled step's time goes, kernel by kernel, measured inside the compiled loop
(Linux ``perf``; no YADE import).

``make bench``'s scale section times each phase of the step called alone from Python, which
adds numba's typing and boxing of every call (docs/physics.md, "Where a contact-step's time
goes"). Sampled inside one compiled call of many steps instead, the shares are the step's
own. ``perf`` cannot name the machine code numba generates in memory, so ``write_map`` writes
the perf map of the running process (``/tmp/perf-<pid>.map``: address, size and name of each
compiled function of drystone's kernels, read from the loaded libraries), and ``profile``
samples the process with ``perf record`` while it runs a function, then sums the samples per
kernel (``perf report``) and per phase of the step (``PHASES``).

``perf`` comes with the kernel's tools (Debian: ``apt-get install linux-perf``); where it is
missing or not allowed (``/proc/sys/kernel/perf_event_paranoid``), ``available`` says why
and nothing is measured.
"""
from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drystone import atomic

#: the step's phases by the kernels that do their work (module.function as ``short_name``
#: gives it; the first matching prefix wins); other kernels are "other". A ``prange`` loop's
#: body is compiled into numba's gufunc (``<dynamic>.__numba_parfor_gufunc``) with the range
#: kernels it calls inlined there (the shapes' placement, the integration), so their work is
#: counted under that name, also on one thread (the kernels cut rows into as many ranges as
#: numba may run threads)
PHASES = (
    ("contact search: clip", ("overlap.",)),
    ("contact search: list and placement", ("neighbours.",)),
    ("damping", ("contact._jacobi", "contact._series_root", "contact._damp_range", "contact._add_body",
                 "contact.damping")),
    ("law", ("contact_rows._law", "contact_rows._global_inverse", "contact_rows._props", "contact.twist_spring",
             "contact.polar_moment", "contact.carried_share")),
    ("sums and energy", ("contact_rows.", "energy.")),
    ("integration", ("integration.",)),
    ("parallel loops (placement, integration) and numba's sorts", ("<dynamic>.", "NRT_", "numba.")),
)


def available() -> str | None:
    """None where ``perf record`` runs here, else why not (one line)."""
    exe = shutil.which("perf")
    if exe is None:
        return "perf not found (Debian: apt-get install linux-perf)"
    with tempfile.TemporaryDirectory() as tmp:
        r = subprocess.run([exe, "record", "-o", str(Path(tmp) / "p.data"), "true"], capture_output=True, text=True)
    if r.returncode != 0:
        last = (r.stderr.strip().splitlines() or ["no message"])[-1]
        return f"perf record fails here: {last}"
    return None


def _names(lib) -> list[str]:
    """The names of the functions a numba code library defines (compiled here, or loaded from
    numba's cache: then the module kept for linking holds them)."""
    names = set()
    for attr in ("_final_module", "_shared_module"):
        mod = getattr(lib, attr, None)
        if mod is not None:
            names |= {f.name for f in mod.functions if not f.is_declaration}
    return sorted(names)


def kernel_addresses() -> dict[int, str]:
    """{address: name} of every compiled function of the drystone kernels loaded in this
    process (every overload of every dispatcher of a loaded drystone module)."""
    from numba.core.registry import CPUDispatcher

    out = {}
    for mname, mod in list(sys.modules.items()):
        if not (mname == "drystone" or mname.startswith("drystone.")) or mod is None:
            continue
        for obj in list(vars(mod).values()):
            if not isinstance(obj, CPUDispatcher):
                continue
            for cres in list(obj.overloads.values()):
                for name in _names(cres.library):
                    try:
                        addr = cres.library.get_pointer_to_function(name)
                    except Exception:  # a name the engine does not resolve: not ours to map
                        continue
                    if addr:
                        out[addr] = name
    return out


def write_map(path: Path | None = None) -> Path:
    """Write this process's perf map (default ``/tmp/perf-<pid>.map``, where perf reads it):
    one line per kernel function, "address size name" in hex, each function's size taken as
    the distance to the next function's address (at most 1 MiB). Returns the path."""
    path = Path(path or f"/tmp/perf-{os.getpid()}.map")
    addrs = kernel_addresses()
    keys = sorted(addrs)
    lines = [f"{a:x} {min(b - a, 1 << 20):x} {addrs[a]}" for a, b in zip(keys, keys[1:] + [keys[-1] + 4096])] \
        if keys else []
    return atomic.write_text(path, "\n".join(lines) + "\n")


_COMPONENT = re.compile(r"(\d+)")


def short_name(symbol: str) -> str:
    """A numba function's mangled name as module.function (``_ZN8drystone9mechanics7overlap
    13_faces_insideB3v58...`` -> ``overlap._faces_inside``; numba's parallel loops as
    ``<dynamic>.__numba_parfor_gufunc``); any other symbol as it is."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        m = _COMPONENT.match(symbol, i)
        n = int(m.group(1))
        start = m.end()
        parts.append(symbol[start:start + n])
        i = start + n
    parts = [p.replace("_3c", "<").replace("_3e", ">") for p in parts]
    if parts and parts[-1].startswith("__numba_parfor_gufunc"):
        parts[-1] = "__numba_parfor_gufunc"
    if parts and parts[0] == "numba":  # numba's own (its sorts, array helpers)
        return "numba." + parts[-1]
    return ".".join(parts[-2:]) if len(parts) >= 2 else symbol


_REPORT_LINE = re.compile(r"^\s*([\d.]+)%\s+\[[.k]\]\s+(\S+)")


def parse_report(text: str) -> dict[str, float]:
    """{short name: percent of the samples} from ``perf report --stdio --no-children --sort
    symbol`` (the lines "  12.34%  [.] symbol"; a kernel's overloads summed)."""
    out: dict[str, float] = {}
    for line in text.splitlines():
        m = _REPORT_LINE.match(line)
        if m:
            name = short_name(m.group(2))
            out[name] = out.get(name, 0.0) + float(m.group(1))
    return out


def phase_of(name: str) -> str:
    """The step's phase a kernel belongs to (``PHASES``), "other" for the rest."""
    for phase, prefixes in PHASES:
        if name.startswith(prefixes):
            return phase
    return "other"


def by_phase(shares: dict[str, float]) -> dict[str, float]:
    """The kernels' shares (%) summed per phase, in PHASES' order, "other" last."""
    out = {p: 0.0 for p, _ in PHASES}
    out["other"] = 0.0
    for name, s in shares.items():
        out[phase_of(name)] += s
    return out


def profile(fn, frequency: int = 2000) -> dict:
    """Run ``fn()`` under ``perf record`` (this process, ``frequency`` samples per second);
    returns {"kernels": {short name: %}, "phases": {phase: %}, "samples_s": the seconds
    sampled, "result": what fn returned}. Compile what ``fn`` runs before (a call that
    compiles inside the window profiles numba's compiler). Raises RuntimeError where
    ``available`` gives a reason."""
    why = available()
    if why:
        raise RuntimeError(why)
    write_map()
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "perf.data"
        perf = subprocess.Popen(["perf", "record", "-F", str(frequency), "-p", str(os.getpid()), "-o", str(data)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(1.0)  # perf attaches
        t0 = time.perf_counter()
        try:
            result = fn()
        finally:
            seconds = time.perf_counter() - t0
            perf.send_signal(signal.SIGINT)
            perf.wait()
        rep = subprocess.run(["perf", "report", "-i", str(data), "--stdio", "--no-children", "--sort", "symbol"],
                             capture_output=True, text=True)
    Path(f"/tmp/perf-{os.getpid()}.map").unlink(missing_ok=True)  # (written above, read by the report)
    shares = parse_report(rep.stdout)
    return {"kernels": dict(sorted(shares.items(), key=lambda kv: -kv[1])), "phases": by_phase(shares),
            "samples_s": seconds, "result": result}
