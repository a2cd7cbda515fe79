"""The Earth orientation of roe_sep.core.frames against ERFA called here directly (IAU 2006/2000A, CIO based, EOP
read here from the IERS file), time scales, the table's ends and a user's EOP file."""

import math
import warnings

import erfa
import numpy as np
import pytest
from astropy_iers_data import IERS_A_FILE

from roe_sep.core import frames
from roe_sep.core.config import ConfigError, scenario_from_dict
from roe_sep.core.od.radar import TIRA, julian_date

ARCSEC = math.pi / 180 / 3600


def iers_table(path=IERS_A_FILE):
    """MJD, UT1-UTC [s], x_p, y_p [arcsec] of the Bulletin A columns, read here (finals2000A ReadMe)."""
    rows = [(float(ln[7:15]), float(ln[58:68]), float(ln[18:27]), float(ln[37:46]))
            for ln in open(path, encoding="ascii") if len(ln) > 68 and ln[58:68].strip()]
    return np.array(rows).T


def reference_itrs_to_gcrs(jd_utc):
    """GCRS <- ITRS of ERFA's IAU 2006/2000A, CIO based (c2i06a, era00, sp00, pom00, c2tcio), UT1 and the pole
    linearly interpolated in the IERS table (no leap second in 2024-2026)."""
    mjd, dut, xp, yp = iers_table()
    m = jd_utc - 2400000.5
    tai1, tai2 = erfa.utctai(jd_utc, 0.0)
    tt1, tt2 = erfa.taitt(tai1, tai2)
    ut1, ut2 = erfa.utcut1(jd_utc, 0.0, np.interp(m, mjd, dut))
    rpom = erfa.pom00(np.interp(m, mjd, xp) * ARCSEC, np.interp(m, mjd, yp) * ARCSEC, erfa.sp00(tt1, tt2))
    rc2t = erfa.c2tcio(erfa.c2i06a(tt1, tt2), erfa.era00(ut1, ut2), rpom)
    return np.swapaxes(rc2t, -1, -2)


def test_tira_in_gcrf_agrees_with_erfa_iau2006_2000a_to_a_metre():
    """312 epochs over 2024-2026: TIRA in the GCRF to <= 1 m (IAU 2000B vs 2006/2000A: millimetres), where the old
    GMST-1982 model of date was 170-302 m off (issue 40)."""
    jd = julian_date("2024-01-01T00:00:00") + np.linspace(0.0, 3 * 365.0, 312) + 0.1234
    ours = np.einsum("nji,j->ni", frames.gcrs_to_itrs(jd), TIRA.ecef)
    ref = np.einsum("nij,j->ni", reference_itrs_to_gcrs(jd), TIRA.ecef)
    err = np.linalg.norm(ours - ref, axis=-1)
    assert np.max(err) < 1.0, np.max(err)
    # the same with the epoch as sim seconds after a day boundary (the radar's form)
    jd0 = julian_date("2025-03-01T00:00:00")
    t = np.array([0.0, 4321.5, 86399.0, 10 * 86400.0 + 17.25])
    np.testing.assert_allclose(frames.gcrs_to_itrs(jd0, t), frames.gcrs_to_itrs(jd0 + t / 86400.0), atol=2e-9)
    # no UT1-UTC or no polar motion is tens of metres: the EOP are applied
    tt = erfa.taitt(*erfa.utctai(jd, 0.0))
    no_eop = erfa.c2t06a(*tt, jd, 0.0, 0.0, 0.0)
    assert np.max(np.linalg.norm(np.einsum("nji,j->ni", no_eop, TIRA.ecef) - ref, axis=-1)) > 10.0


def test_time_scales():
    jd = julian_date("2017-01-01T00:00:00")
    tai = frames.utc_to_tai(jd, 0.0)
    assert (tai[0] - jd + tai[1]) * 86400.0 == pytest.approx(37.0, abs=1e-6)  # TAI-UTC since 2017
    assert sum(frames.utc_to_tai(julian_date("2016-07-01T00:00:00"), 0.0)) * 86400.0 - \
        julian_date("2016-07-01T00:00:00") * 86400.0 == pytest.approx(36.0, abs=1e-4)
    tt = frames.tai_to_tt(*tai)
    assert (sum(tt) - sum(tai)) * 86400.0 == pytest.approx(32.184, abs=1e-4)
    gps = frames.tai_to_gps(*tai)
    assert (sum(tai) - sum(gps)) * 86400.0 == pytest.approx(19.0, abs=1e-4)
    assert (sum(frames.utc_to_tt(jd, 0.0)) - jd) * 86400.0 == pytest.approx(69.184, abs=1e-4)
    mjd, dut, _, _ = iers_table()
    k = int(np.searchsorted(mjd, jd - 2400000.5))
    ut1 = frames.utc_to_ut1(jd, 0.0)
    assert ((ut1[0] - jd) + ut1[1]) * 86400.0 == pytest.approx(dut[k], abs=1e-6)
    # vectorized over epochs
    assert frames.utc_to_tt(np.full(5, jd), np.linspace(0, 1, 5))[0].shape == (5,)


def test_epochs_beyond_the_table_warn_once_and_hold_ut1_with_no_polar_motion():
    mjd, dut, _, _ = iers_table()
    frames._warned.clear()
    far = 2400000.5 + mjd[-1] + 400.0
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d, xp, yp = frames.earth_orientation(far)
        frames.earth_orientation(far + 1.0)
    msgs = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    assert len(msgs) == 1 and "outside the EOP table" in msgs[0] and "earth.eop_file" in msgs[0]
    assert float(d) == pytest.approx(dut[-1], abs=2e-3) and float(xp) == 0.0 and float(yp) == 0.0
    inside = frames.earth_orientation(2400000.5 + mjd[100])
    assert float(inside[1]) != 0.0


def test_a_users_eop_file_from_the_scenario(tmp_path):
    """A shifted copy of the IERS file (UT1-UTC + 0.1 s) named by the scenario's earth.eop_file turns the Earth by
    0.1 s of rotation (29 m at TIRA); a bad file is a ConfigError naming it."""
    jd = julian_date("2025-06-01T00:00:00")
    before = frames.gcrs_to_itrs(jd).T @ TIRA.ecef
    lines = []
    for ln in open(IERS_A_FILE, encoding="ascii"):
        if len(ln) > 68 and ln[58:68].strip():
            ln = ln[:58] + f"{float(ln[58:68]) + 0.1:10.7f}" + ln[68:]
        lines.append(ln)
    shifted = tmp_path / "finals2000A.shifted"
    shifted.write_text("".join(lines), encoding="ascii")
    try:
        scenario = scenario_from_dict({"earth": {"eop_file": str(shifted)}})
        assert scenario.earth.eop_file == str(shifted)
        after = frames.gcrs_to_itrs(jd).T @ TIRA.ecef
        moved = np.linalg.norm(after - before)
        assert moved == pytest.approx(0.1 * 7.292115e-5 * math.hypot(TIRA.ecef[0], TIRA.ecef[1]), rel=1e-3)
        bad = tmp_path / "bad.all"
        bad.write_text("not an EOP file\n" * 3 + "73 1 2 41684.00 I  x.120733 0.009786  0.136966 0.015902  I "
                       "0.8084178 0.0002710\n", encoding="ascii")
        with pytest.raises(ConfigError, match="earth.eop_file: EOP file .*bad.all line 4"):
            scenario_from_dict({"earth": {"eop_file": str(bad)}})
        with pytest.raises(ConfigError, match="earth.eop_file"):
            scenario_from_dict({"earth": {"eop_file": str(tmp_path / "missing")}})
    finally:
        frames.use_eop_file(None)
    np.testing.assert_allclose(frames.gcrs_to_itrs(jd).T @ TIRA.ecef, before, atol=1e-9)
