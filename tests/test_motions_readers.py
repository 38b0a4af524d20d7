"""Readers on small fixture files written by the tests (well-formed and malformed).

Values are written with at least 6 significant digits, so readbacks are compared with a
relative tolerance of 1e-12 (tolerances.READER_REL: the conversion factors are exact
decimal multiples, gal = 0.01 m/s^2, g = 9.80665 m/s^2).
"""
from __future__ import annotations

import numpy as np
import pytest

import tolerances as tol
from drystone.motions import readers
from drystone.motions.readers import RecordFormatError
from drystone.motions.record import G

AT2_WEST2 = """PEER NGA STRONG MOTION DATABASE RECORD
Kobe, Japan, 1/16/1995, Nishi-Akashi, 0
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=    7, DT=   .0100 SEC
  0.1000000E-01 -0.2000000E-01  0.3000000E-01  0.5000000E+00
 -0.1000000E-01  0.0000000E+00  0.1000000E-01
"""

AT2_WEST1 = """PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.
KOBE 01/16/95 2046, NISHI-AKASHI, 000
ACCELERATION TIME HISTORY IN UNITS OF G
   5    0.0100    NPTS, DT
 .1 .2 -.3 .2 .1
"""

JMA = """SITE CODE= 630
LAT.= 34.6917
LON.= 135.1772
SAMPLING RATE= 100Hz
UNIT  = gal
INITIAL TIME = 1995 01 17 05 46 47
 NS, EW, UD
 -0.5,  0.1,  0.2
 818.0, -20.0, 3.0
 -1.5,  2.0, -4.0
 4.0,  5.0,  6.0
"""

CISMID = """RED ACELEROGRAFICA DEL CISMID (REDACIS)
NOMBRE DE LA ESTACION : Tambomachay
CODIGO DE LA ESTACION : TMB
FECHA DEL SISMO : 27/09/2014
NUMERO DE MUESTRAS : 4
FRECUENCIA DE MUESTREO : 100 Hz
UNIDADES : cm/s2 (gal)
      E-W        N-S        U-D
     1.0       10.0      -3.0
     2.0      -20.0       4.0
     3.0       30.0      -5.0
     4.0      -40.0       6.0
"""


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_peer_west2_units_and_header(tmp_path):
    r = readers.read(write(tmp_path, "x.AT2", AT2_WEST2))
    assert r.n == 7 and r.dt == pytest.approx(0.01)
    assert r.pga == pytest.approx(0.5 * G, rel=tol.READER_REL)
    assert r.event == "Kobe, Japan, 1/16/1995" and r.station == "Nishi-Akashi" and r.component == "0"
    assert r.units_in_file.upper() == "G" and r.source.endswith("x.AT2")


def test_peer_west1_header(tmp_path):
    r = readers.read(write(tmp_path, "y.at2", AT2_WEST1))
    assert r.n == 5 and r.dt == pytest.approx(0.01) and r.station == "NISHI-AKASHI" and r.component == "000"
    np.testing.assert_allclose(r.acc, np.array([0.1, 0.2, -0.3, 0.2, 0.1]) * G, rtol=tol.READER_REL)


def test_peer_count_mismatch_is_an_error_naming_file_and_line(tmp_path):
    p = write(tmp_path, "short.AT2", AT2_WEST2.replace("NPTS=    7", "NPTS=    8"))
    with pytest.raises(RecordFormatError, match=r"short\.AT2:4: .*NPTS=8.*7 values"):
        readers.read(p)


def test_peer_bad_number_names_line(tmp_path):
    p = write(tmp_path, "bad.AT2", AT2_WEST2.replace("-0.1000000E-01", "-0.1000x00E-01"))
    with pytest.raises(RecordFormatError, match=r"bad\.AT2:6: not a number"):
        readers.read(p)


def test_peer_bad_header(tmp_path):
    p = write(tmp_path, "hdr.AT2", AT2_WEST2.replace("NPTS=    7, DT=   .0100 SEC", "something else"))
    with pytest.raises(RecordFormatError, match=r"hdr\.AT2:4:"):
        readers.read(p)


def test_jma_csv_components_and_gal(tmp_path):
    p = write(tmp_path, "kobe.csv", JMA)
    assert readers.detect_format(p) == "jma"
    ns = readers.read(p)  # default NS, the component Ogawa et al. used
    assert ns.component == "NS" and ns.station == "630" and ns.dt == pytest.approx(0.01)
    assert ns.pga == pytest.approx(8.18, rel=tol.READER_REL) and ns.units_in_file == "gal"
    ew = readers.read(p, component="E-W")
    np.testing.assert_allclose(ew.acc, [0.001, -0.2, 0.02, 0.05], rtol=tol.READER_REL)
    assert len(readers.read_all(p)) == 3
    with pytest.raises(RecordFormatError, match="no component 'X'"):
        readers.read(p, component="X")


def test_jma_malformed_row_and_missing_rate(tmp_path):
    p = write(tmp_path, "bad.csv", JMA.replace(" -1.5,  2.0, -4.0", " -1.5,  2.0"))
    with pytest.raises(RecordFormatError, match=r"bad\.csv:10: expected 3 values, got 2"):
        readers.read(p)
    p = write(tmp_path, "norate.csv", JMA.replace("SAMPLING RATE= 100Hz\n", ""))
    with pytest.raises(RecordFormatError, match="no SAMPLING RATE"):
        readers.read(p, format="jma")
    assert readers.read(p, format="jma", dt=0.01).n == 4


def test_cismid_labels_in_any_order(tmp_path):
    p = write(tmp_path, "tmb.txt", CISMID)
    assert readers.detect_format(p) == "cismid"
    ns = readers.read(p)
    np.testing.assert_allclose(ns.acc, [0.1, -0.2, 0.3, -0.4], rtol=tol.READER_REL)
    assert ns.component == "NS" and ns.station == "Tambomachay" and ns.dt == pytest.approx(0.01)
    assert "27/09/2014" in ns.event
    ud = readers.read(p, component="UD")
    np.testing.assert_allclose(ud.acc, [-0.03, 0.04, -0.05, 0.06], rtol=tol.READER_REL)


def test_cismid_without_labels_takes_ns_ew_ud_and_says_so(tmp_path):
    text = CISMID.replace("      E-W        N-S        U-D\n", "")
    r = readers.read(write(tmp_path, "nolab.txt", text), format="cismid")
    np.testing.assert_allclose(r.acc, [0.01, 0.02, 0.03, 0.04], rtol=tol.READER_REL)
    assert any("columns taken as NS, EW, UD" in h for h in r.history)


def test_cismid_sample_count_checked(tmp_path):
    p = write(tmp_path, "cnt.txt", CISMID.replace("NUMERO DE MUESTRAS : 4", "NUMERO DE MUESTRAS : 5"))
    with pytest.raises(RecordFormatError, match=r"cnt\.txt:9: the header declares 5 samples but the file has 4"):
        readers.read(p)
    p = write(tmp_path, "row.txt", CISMID.replace("     3.0       30.0      -5.0", "     3.0       3O.0      -5.0"))
    with pytest.raises(RecordFormatError, match=r"row\.txt:11:"):
        readers.read(p)


def test_plain_one_column_needs_dt_and_units(tmp_path):
    p = write(tmp_path, "a.txt", "0.1\n-0.2\n0.3\n")
    with pytest.raises(RecordFormatError, match="pass dt="):
        readers.read(p, units="m/s^2")
    with pytest.raises(RecordFormatError, match="units"):
        readers.read(p, dt=0.01)
    r = readers.read(p, dt=0.01, units="g")
    np.testing.assert_allclose(r.acc, np.array([0.1, -0.2, 0.3]) * G, rtol=tol.READER_REL)


def test_plain_two_columns_and_header_comments(tmp_path):
    p = write(tmp_path, "b.dat", "# units = gal\n# station = X\n0.50 1\n0.52 2\n0.54 -3\n0.56 4\n")
    r = readers.read(p)
    assert r.dt == pytest.approx(0.02) and r.start_time == pytest.approx(0.5) and r.station == "X"
    np.testing.assert_allclose(r.acc, [0.01, 0.02, -0.03, 0.04], rtol=tol.READER_REL)
    with pytest.raises(RecordFormatError, match="declares units 'gal' but units='g'"):
        readers.read(p, units="g")


def test_plain_non_uniform_time_is_an_error_not_a_resampling(tmp_path):
    p = write(tmp_path, "nu.txt", "# units = m/s^2\n0.0 1\n0.01 2\n0.02 3\n0.04 4\n0.05 5\n")
    with pytest.raises(RecordFormatError, match=r"nu\.txt:.*non-uniform time step"):
        readers.read(p)


def test_plain_garbage_line(tmp_path):
    p = write(tmp_path, "g.txt", "# dt = 0.01\n# units = g\n0.1\n0.2\nabc\n0.3\n")
    with pytest.raises(RecordFormatError, match=r"g\.txt:5: not a number"):
        readers.read(p)


def test_obspy_sac_declares_acceleration_and_mseed_needs_units(tmp_path):
    import obspy
    from obspy.io.sac import SACTrace

    data = np.array([0.0, 1.0e9, -2.0e9, 0.5e9], dtype=np.float32)  # nm/s^2
    sac = SACTrace(data=data, delta=0.005, kstnm="WNQ", kcmpnm="HNN", idep="iacc")
    sp = tmp_path / "w.sac"
    sac.write(str(sp))
    r = readers.read(sp)
    assert r.units_in_file == "nm/s^2" and r.dt == pytest.approx(0.005) and r.station == "WNQ"
    np.testing.assert_allclose(r.acc, [0.0, 1.0, -2.0, 0.5], rtol=tol.FLOAT32_REL)  # float32 samples

    tr = obspy.Trace(data=np.array([1, -2, 3], dtype=np.int32), header={"delta": 0.01, "station": "TMB",
                                                                      "channel": "HNE"})
    mp = tmp_path / "t.mseed"
    tr.write(str(mp), format="MSEED")
    with pytest.raises(RecordFormatError, match=r"t\.mseed: .*pass units="):
        readers.read(mp)
    r = readers.read(mp, units="gal")
    np.testing.assert_allclose(r.acc, [0.01, -0.02, 0.03], rtol=tol.READER_REL)
    assert r.component == "HNE"


def test_missing_file():
    with pytest.raises(FileNotFoundError):
        readers.read("/nonexistent/record.AT2")
