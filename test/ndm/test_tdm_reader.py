"""The TDM reader (roe_sep.ndm.tdm_reader) on public CCSDS example files (test/data/ccsds_examples, PROVENANCE.md)
and on variants of our own TDM: every file is read with its values checked against the file, or refused in one
line naming the keyword and its value."""

from datetime import datetime, timedelta, timezone
from pathlib import Path

import numpy as np
import pytest

from roe_sep.errors import NdmError
from roe_sep.ndm import messages as ndm
from roe_sep.ndm import tdm_reader
from roe_sep.ndm.tdm_reader import C_LIGHT

DATA = Path(__file__).resolve().parents[1] / "data" / "ccsds_examples"
EPOCH = "2016-07-01T00:00:00"
UTC = timezone.utc


def read_observations(source, span=None):
    return tdm_reader.read_observations(ndm.read_message(source), span)


def _ours(**replace):
    """Our own KVN TDM (two time tags, 100 s and 200 s after EPOCH), with text replacements."""
    p = ndm.TrackingPass("TIRA", 4, np.array([100.0, 200.0]), np.array([[1.7e6, 2.4, 0.19], [1.6e6, 2.5, 0.2]]),
                         10.0, 1.7e-4)
    text = ndm.to_text(ndm.build_tdm(EPOCH, [p]), "kvn")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


def _refused(source, match, span=None):
    with pytest.raises(NdmError, match=match) as info:
        read_observations(source, span)
    assert "\n" not in str(info.value)
    return str(info.value)


@pytest.mark.parametrize("name, match", [
    ("TDMExample2.txt", r"segment 1: no RANGE, ANGLE_1 or ANGLE_2 to read \(its data: RECEIVE_FREQ_1, "
                        r"TRANSMIT_FREQ_2\)"),  # NASA/JPL: one-way Doppler (frequencies) only
    ("TDMExample6.txt", "PATH 1,2,3,2,1 is not supported"),  # JAXA: a relay (the AttributeError)
    ("TDMExample6.xml", "PATH 1,2,3,2,1 is not supported"),  # the same in XML
    ("TDMExample8.txt", "segment 1: ANGLE_TYPE XSYE is not supported"),  # GSOC: X/Y angles
])
def test_public_examples_we_do_not_read_are_refused_in_one_line(name, match):
    _refused(DATA / name, match)
    with pytest.raises(NdmError, match=match):  # and so by the radar reader, whatever the run's epoch
        ndm.read_tdm(DATA / name, "1998-06-01T00:00:00", 10.0, 1e-4)


def test_nasa_range_units_example_is_read_with_its_frequencies_and_delays():
    obs = read_observations(DATA / "TDMExample4.txt")  # 1.0, PATH 1,2,1, RU, X-band uplink, CORRECTIONS_APPLIED YES
    assert len(obs) == 5 and all(o.path == (1, 2, 1) and o.timetag_ref == "RECEIVE" for o in obs)
    assert obs[0].participants == ("DSS-24", "yyyy-nnnA", "DSS-24")
    k = 221.0 / (749.0 * 2.0)  # DSN range units for an X-band uplink
    delays = 7.7e-5 + 0.0 + 0.0 + 7.7e-5  # TRANSMIT_DELAY_1, _2, RECEIVE_DELAY_2, _1
    for o, ru, f, tag in ((obs[0], 39242998.5151986, 7180064367.3536, "2005-07-10T00:31:51"),
                          (obs[-1], 35478729.4012973, 7180065326.56141, "2005-07-10T00:58:24")):
        rng = (ru / (k * f) - delays) * C_LIGHT / 2.0
        assert o.range_m == pytest.approx(rng, rel=1e-12)
        assert o.timetag == o.receive_epoch == datetime.fromisoformat(tag).replace(tzinfo=UTC)
        assert (o.timetag - o.epoch).total_seconds() == pytest.approx(rng / C_LIGHT, abs=1e-6)
    assert 5.5e6 < obs[0].range_m < 5.6e6
    msg = _refused(DATA / "TDMExample4.txt", "outside the span", span=(EPOCH, "2016-08-01T00:00:00"))
    assert "2005-191T00:31:51 UTC" in msg and "2016-07-01T00:00:00+00:00 to 2016-08-01T00:00:00+00:00" in msg


def test_gsoc_azel_segment_in_seconds_is_read():
    text = (DATA / "TDMExample8.txt").read_text()
    second = text[:text.index("META_START")] + text[text.index("META_START", text.index("DATA_STOP")):]
    obs = read_observations(second)  # RANGE_UNITS s, AZEL, Doppler alongside (left aside)
    assert len(obs) == 3 and {o.participants for o in obs} == {("WHM1", "SAT", "WHM1")}
    assert obs[0].range_m == pytest.approx(4.00165248953670e4 * C_LIGHT / 2.0, rel=1e-12)
    assert np.degrees([obs[0].angle_1, obs[0].angle_2]) == pytest.approx([99.53204250, 1.26724167], abs=1e-9)
    assert np.degrees([obs[-1].angle_1, obs[-1].angle_2]) == pytest.approx([243.73365222, 8.78254167], abs=1e-9)
    assert obs[-1].timetag == datetime(2007, 8, 29, 13, 0, 2, tzinfo=UTC)


def test_public_opm_and_oem_examples_are_read_with_their_values():
    opm = ndm.read_message(DATA / "OPMExample1.txt")  # JAXA, earth-fixed
    assert opm.body.segment.metadata.ref_frame == "ITRF2000"
    sv = opm.body.segment.data.state_vector
    assert (sv.x.value, sv.y_dot.value, sv.z_dot.value) == (6503.514, 8.74042, -4.191076)
    oem = ndm.read_message(DATA / "OEMExample1.txt")  # NASA/JPL, Mars-centred
    states = oem.body.segment[0].data.state_vector
    assert len(states) == 4 and oem.body.segment[0].metadata.center_name == "MARS BARYCENTER"
    assert (states[0].x.value, states[-1].z_dot.value) == (2789.619, 1.63861)
    with pytest.raises(NdmError, match="expected a TDM, got OEM"):
        ndm.read_tdm(DATA / "OEMExample1.txt", EPOCH, 10.0, 1e-4)


@pytest.mark.parametrize("system, minus_utc", [("UTC", 0.0), ("TAI", 36.0), ("GPS", 17.0), ("TT", 68.184)])
def test_time_systems_become_utc(system, minus_utc):
    obs = read_observations(_ours(**{"= UTC": f"= {system}"}))
    tag = datetime(2016, 7, 1, 0, 1, 40, tzinfo=UTC) - timedelta(seconds=minus_utc)  # TAI-UTC = 36 s in 2016
    assert obs[0].timetag == tag
    assert obs[0].range_m == pytest.approx(1.7e6, abs=1e-6) and obs[0].angle_type == "AZEL"
    assert obs[0].epoch == tag - timedelta(seconds=round(1.7e6 / C_LIGHT, 6))  # two-way, RECEIVE: at the bounce


def test_one_way_and_transmit_time_tags():
    tag = datetime(2016, 7, 1, 0, 1, 40, tzinfo=UTC)
    tau = timedelta(seconds=round(1.7e6 / C_LIGHT, 6))
    down = read_observations(_ours(**{"PATH                     = 1,2,1": "PATH = 2,1"}))[0]
    assert (down.epoch, down.receive_epoch, down.range_m) == (tag - tau, tag, pytest.approx(1.7e6, abs=1e-6))
    up = read_observations(_ours(**{"PATH                     = 1,2,1": "PATH = 1,2"}))[0]
    assert (up.epoch, up.receive_epoch) == (tag, tag)  # received at the spacecraft at the time tag
    sent = read_observations(_ours(**{"= RECEIVE": "= TRANSMIT"}))[0]
    assert (sent.epoch, sent.receive_epoch) == (tag + tau, tag + timedelta(seconds=2 * 1.7e6 / C_LIGHT))
    t = ndm.read_tdm(_ours(**{"= RECEIVE": "= TRANSMIT"}), EPOCH)[0].t  # the radar's stamp: the station receives
    assert t == pytest.approx(100.0 + 2 * 1.7e6 / C_LIGHT, abs=2e-6)


def test_corrections_are_added_unless_applied():
    meta = "ANGLE_TYPE               = AZEL"
    text = _ours(**{meta: meta + "\nCORRECTION_RANGE = 0.002\nCORRECTION_ANGLE_2 = -0.5\nCORRECTIONS_APPLIED = NO"})
    o = read_observations(text)[0]
    assert o.range_m == pytest.approx(1.7e6 + 2.0, abs=1e-6)
    assert np.degrees(o.angle_2) == pytest.approx(np.degrees(0.19) - 0.5, abs=1e-9)
    o = read_observations(text.replace("= NO", "= YES"))[0]
    assert o.range_m == pytest.approx(1.7e6, abs=1e-6) and o.angle_2 == pytest.approx(0.19, abs=1e-12)


def test_range_units_need_a_transmit_frequency_and_a_known_band():
    ru = {"RANGE_UNITS              = km": "RANGE_UNITS = RU"}
    _refused(_ours(**ru), "RANGE_UNITS RU needs the path's TRANSMIT_FREQ")
    freq = "DATA_START\nTRANSMIT_FREQ_1 = 2016-07-01T00:01:40 2.1e9\n"
    o = read_observations(_ours(**ru, **{"DATA_START\n": freq}))[0]  # S band: 1 RU = 2 / f_T s of light time
    assert o.range_m == pytest.approx(1700.0 / (0.5 * 2.1e9) * C_LIGHT / 2.0, rel=1e-12)
    _refused(_ours(**ru, **{"DATA_START\n": freq.replace("2.1e9", "3.2e10")}), r"uplink 32000000000.0 Hz")


@pytest.mark.parametrize("replace, match", [
    ({"= UTC": "= TDB"}, "TIME_SYSTEM TDB is not supported"),
    ({"= km": "= m"}, "'m' is not a valid RangeUnitsType"),  # not a 503.0 unit: the library refuses the file
    ({"= AZEL": "= XSYE"}, "ANGLE_TYPE XSYE is not supported"),
    ({"= 1,2,1": "= 1,2,3"}, "PATH 1,2,3 is not supported"),
    ({"= 1,2,1": "= 1,2\nPATH_1 = 2,1"}, "PATH_1 2,1 is not supported"),
    ({"= 1,2,1": "= 2,3"}, "PATH 2,3 does not start or end at PARTICIPANT_1"),
    ({"= RECEIVE": "= RECEIVE\nRANGE_MODULUS = 1000"}, r"RANGE_MODULUS 1000.0 KM leaves the range ambiguous"),
    ({"= RECEIVE": "= RECEIVE\nRANGE_MODULUS = 1e9"}, None),  # large enough: read
    ({"ANGLE_2                  = 2016-07-01T00:01:40.000000  10.886198107485642": ""}, "come in pairs"),
])
def test_what_is_refused_is_named_in_one_line(replace, match):
    if match is None:
        assert len(read_observations(_ours(**replace))) == 2
    else:
        _refused(_ours(**replace), match)


def test_radar_reader_refuses_what_the_radar_does_not_measure():
    with pytest.raises(NdmError, match="PATH 1,2 ends at the spacecraft"):
        ndm.read_tdm(_ours(**{"= 1,2,1": "= 1,2"}), EPOCH)
    with pytest.raises(NdmError, match="outside the span"):  # 9 years before the run's epoch
        ndm.read_tdm(_ours(), "2025-07-01T00:00:00")
    big = _ours(**{"TRACK_ID                 = TIRA_PASS_4": "TRACK_ID = TIRA_PASS_99999999999"})
    assert {m.pass_id for m in ndm.read_tdm(big, EPOCH)} == {1}  # not a uint32: the segment's index
