"""Operational plan (seed 001 Sec. 5): skyfield with the shipped DE421, contacts, radar, eclipses, ranked windows."""

import datetime
import json
import math

import numpy as np
import pytest

from roe_sep.cli import main
from roe_sep.core.od.radar import raan_from_sun
from roe_sep.core.ops import plan as ops
from roe_sep.core.relmotion.orbit import angle_between

CFG = ops.load_ops_config()
REP = ops.plan(CFG, datetime.date(2016, 7, 1), days=2.0)


def _t(s):
    return datetime.datetime.strptime(s, "%Y-%m-%dT%H:%M:%SZ")


def test_ltan_raan_hand_value():
    assert raan_from_sun(0.0, 18.0) == pytest.approx(math.radians(90.0))
    assert raan_from_sun(math.radians(100.0), 21.5) == pytest.approx(math.radians(100.0 + 142.5))


def test_argument_of_latitude_and_rtn_of_a_circular_orbit():
    inc, raan = math.radians(97.0), math.radians(30.0)
    u = np.radians([10.0, 100.0, 250.0])
    node = np.array([math.cos(raan), math.sin(raan), 0.0])
    y = np.array([-math.sin(raan) * math.cos(inc), math.cos(raan) * math.cos(inc), math.sin(inc)])
    r = np.outer(node, np.cos(u)) + np.outer(y, np.sin(u))
    v = -np.outer(node, np.sin(u)) + np.outer(y, np.cos(u))
    np.testing.assert_allclose(ops.argument_of_latitude(r, v), u)
    np.testing.assert_allclose(ops.rtn_to_inertial(r, v, [0.0, 1.0, 0.0]), v, atol=1e-12)  # T along v
    assert np.degrees(angle_between(r, v, axis=0)) == pytest.approx([90.0] * 3)


def test_intervals():
    t = list(range(8))
    assert ops.intervals([1, 1, 0, 0, 1, 0, 1, 1], t) == [(0, 1), (4, 4), (6, 7)]


def test_plan_2016_07_01_structure():
    assert {"contacts", "radar_passes", "eclipses", "windows"} <= REP.keys()
    assert {c["station"] for c in REP["contacts"]} == {"OHIG", "INUV", "SPZBG", "WHM1"}
    # a polar LEO is seen by TIRA ~2 times in a row twice a day (seed 001: ~19:35/21:10 and ~8:30/10:10)
    assert 6 <= len(REP["radar_passes"]) <= 10
    p = REP["period_s"]
    assert p == pytest.approx(2 * math.pi / 1.1031727e-3, rel=1e-6)
    # an eclipse every orbit in July at 09:30 LTDN, each shorter than 40 % of the period
    assert len(REP["eclipses"]) >= 28
    assert all(e["duration_s"] < 0.4 * p for e in REP["eclipses"])


def test_windows_follow_the_rules():
    ws = REP["windows"]
    assert [w["rank"] for w in ws] == list(range(1, len(ws) + 1))
    best = ws[0]
    assert best["eligible"] and best["sunlit"] and best["sun_angle_deg"] >= 30.0
    assert any(c["station"] in best["stations"] and _t(c["start"]) <= _t(best["start"]) <= _t(c["end"])
               for c in REP["contacts"])
    delay = (_t(best["first_radar"]) - _t(best["start"])).total_seconds()
    assert delay >= 1.5 * REP["period_s"]
    assert best["backup_radar"] and best["confirm_radar"]
    gap = (_t(best["confirm_radar"]) - _t(best["first_radar"])).total_seconds() / 3600
    assert 11.0 <= gap <= 16.0
    for w in ws:
        if not w["eligible"]:
            assert any(r.startswith("REJECT") for r in w["reasons"])
    # seed 001 Sec. 5: in July the Antarctic (south pole, u = 270 deg) passes are in Earth shadow
    assert all(not w["eligible"] for w in ws if w["pole"] == "south")


def test_cli_ops_json_and_timeline(capsys, tmp_path):
    png = tmp_path / "timeline.png"
    assert main(["ops", "--date", "2016-07-01", "--days", "1", "--plot", str(png), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    for key in ("contacts", "radar_passes", "eclipses", "windows"):
        assert key in rep
    assert {"start", "station", "reasons"} <= rep["windows"][0].keys()
    assert png.stat().st_size > 10_000


def test_cli_ops_bad_date(capsys):
    with pytest.raises(SystemExit):
        main(["ops", "--date", "2016-13-01"])
    err = capsys.readouterr().err
    assert "--date" in err and "YYYY-MM-DD" in err and "2016-13-01" in err and len(err.strip().splitlines()) == 1


# a BIROS-like element set; column 69 of each line is its checksum (sgp4.io.compute_checksum: 6 and 4)
LINE1 = "1 41604U 16040F   16183.50000000  .00000500  00000-0  25000-4 0  9996"
LINE2 = "2 41604  97.4500 250.0000 0010000  90.0000 270.0000 15.18000000  1004"


def test_tle_file(tmp_path, capsys):
    tle = tmp_path / "c.tle"
    tle.write_text(f"BIROS\n{LINE1}\n{LINE2}\n")
    assert main(["ops", "--date", "2016-07-01", "--days", "0.5", "--tle", str(tle), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["orbit"] == "tle"
    bad = tmp_path / "bad.tle"
    bad.write_text("nothing\n")
    assert main(["ops", "--date", "2016-07-01", "--tle", str(bad)]) == 2


@pytest.mark.parametrize("line1, line2, line", [(LINE1[:-1] + "7", LINE2, 1), (LINE1, LINE2[:-1] + "5", 2),
                                               (LINE1, LINE2[:-1], 2), (LINE1[:-1] + "0", LINE2[:-1] + "0", 1)])
def test_tle_checksum_refused_naming_the_line(tmp_path, capsys, line1, line2, line):
    """A TLE line whose column 69 is not the modulo-10 sum of its columns 1-68 (or missing) is refused on one line
    naming that line; sgp4's own parser reads such a line without complaint."""
    from sgp4.api import Satrec

    Satrec.twoline2rv(line1, line2)  # what was accepted without the check
    tle = tmp_path / "c.tle"
    tle.write_text(f"{line1}\n{line2}\n")
    assert main(["ops", "--date", "2016-07-01", "--days", "0.5", "--tle", str(tle)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(tle) in err and f"line {line} " in err, err
    assert ("checksum" in err) if len((line1, line2)[line - 1]) == 69 else ("not 69" in err)
