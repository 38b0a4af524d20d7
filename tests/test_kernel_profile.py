"""drystone.kernel_profile: the perf map of the loaded kernels and the reading of perf's report
(perf itself is not needed: the bench's profile section runs it)."""
import os

import numpy as np

from drystone import kernel_profile as kp

REPORT = """# Samples: 11K of event 'cpu-clock:ppp'
#
    23.17%  [.] _ZN8drystone9mechanics7overlap13_faces_insideB3v46B36c8tJTIcFKzyF2ILShI4CrgQEltYEAA_3dE5A
    16.13%  [.] _ZN8drystone9mechanics7contact12_jacobi_sqrtB3v94B36c8tJTIcFKzyF2ILShI4CrgQEltYEAA_3
            |--5.31%--0x3a88c240c4aecb14
    15.04%  [.] _ZN8drystone9mechanics7overlap13_faces_insideB3v49B36c8tJTIcFKzyF2ILShI4CrgQEltYEAA_
     3.44%  [.] _ZN8drystone9mechanics12contact_rows10_law_rangeB3v40B36c8tJTIcFKzyF2ILShI4CrgQEltYE
     2.52%  [.] _ZN13_3cdynamic_3e36__numba_parfor_gufunc_0x7f095a6c4250B3v99B104c8tJTC_2fWQAlzW1yBD
     0.54%  [.] _ZN5numba4misc9mergesort19make_mergesort_impl12_3clocals_3e18argmergesort_innerB4v121
     0.22%  [.] __memset_avx2_unaligned_erms
     0.09%  [k] _raw_spin_unlock_irqrestore
"""


def test_numba_names_read_as_module_and_function():
    assert kp.short_name("_ZN8drystone9mechanics7overlap13_faces_insideB3v46B36c8tJTIcFKzyF2") == "overlap._faces_inside"
    assert kp.short_name("_ZN13_3cdynamic_3e36__numba_parfor_gufunc_0x7f095a6c4250B3v99") == \
        "<dynamic>.__numba_parfor_gufunc"
    assert kp.short_name("_ZN5numba4misc9mergesort19make_mergesort_impl12_3clocals_3e18argmergesort_innerB4v1") == \
        "numba.argmergesort_inner"
    assert kp.short_name("__memset_avx2_unaligned_erms") == "__memset_avx2_unaligned_erms"


def test_the_report_is_summed_by_kernel_and_by_phase():
    """A kernel's overloads add up; call-graph lines are not samples; every sample lands in one
    phase (the shares are exact decimal sums of the report's)."""
    k = kp.parse_report(REPORT)
    assert abs(k["overlap._faces_inside"] - (23.17 + 15.04)) < 1e-12
    assert len(k) == 7  # the two overloads of _faces_inside are one kernel
    ph = kp.by_phase(k)
    assert abs(ph["contact search: clip"] - 38.21) < 1e-12
    assert abs(ph["damping"] - 16.13) < 1e-12 and abs(ph["law"] - 3.44) < 1e-12
    assert abs(ph["parallel loops (placement, integration) and numba's sorts"] - (2.52 + 0.54)) < 1e-12
    assert abs(ph["other"] - (0.22 + 0.09)) < 1e-12
    assert abs(sum(ph.values()) - sum(k.values())) < 1e-9


def test_the_map_names_the_loaded_kernels_at_their_addresses(tmp_path):
    """After a kernel has run, the map holds it: one line per function, "address size name" in
    hex, addresses increasing, each function's extent ending where the next begins."""
    from drystone.mechanics import contact

    n = np.array([0.0, 0.0, 1.0])
    assert contact.polar_moment(n, np.diag([2.0, 3.0, 0.0])) == 5.0  # (the kernel compiled or loaded)
    path = kp.write_map(tmp_path / "perf.map")
    rows = [ln.split(" ", 2) for ln in path.read_text().splitlines()]
    addrs = [int(a, 16) for a, _, _ in rows]
    sizes = [int(s, 16) for _, s, _ in rows]
    assert addrs == sorted(set(addrs)) and all(s > 0 for s in sizes)
    assert all(a + s <= b for a, s, b in zip(addrs, sizes, addrs[1:]))
    assert "contact.polar_moment" in {kp.short_name(name) for _, _, name in rows}
    assert not any(p.name.endswith(".part") for p in tmp_path.iterdir())
    assert kp.write_map().name == f"perf-{os.getpid()}.map"
    os.remove(f"/tmp/perf-{os.getpid()}.map")
