"""Fault injection on the command line: a table of bad inputs over every ``roe-sep`` subcommand and numeric option,
the configuration files they read and damaged bags.

Each case runs in-process (``roe_sep.cli.main``, output captured) under a wall-time alarm and is classified:

* ``ok``: the expected exit status; for bad input (2) exactly one line on stderr that names the option or file and
  the value given, no traceback; for a damaged bag an honest report (exit 1, the damage named);
* ``traceback``: an exception escaped ``main`` or exit 3 (internal error);
* ``silent``: exit 0 on bad input;
* ``hang``: the alarm fired;
* ``multiline``: the right exit status but the error spans several lines;
* ``numpy``: a NumPy repr in the output (``np.float64(0.0)``, ``array([...])``) instead of the plain value;
* ``wrong``: another exit status or a message that does not name the option and value.

Each case is its own test (every check holds under ``-k`` and ``-x``); the table covers every subcommand, and the
number of cases the docs quote is the table's (``test_the_table_covers_every_subcommand_as_the_docs_say``). Then
every subcommand's ``--json`` output (tiny sample
counts) is parsed with a strict parser that refuses NaN/Infinity. Marked ``fault``: ``pytest -m fault`` runs it
alone, ``-m 'not fault'`` skips it.
"""

import collections
import json
import re
import shutil
import signal
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from roe_sep.cli import main

pytestmark = pytest.mark.fault

ROOT = Path(__file__).resolve().parents[2]
TIMEOUT_S = 20  # per case; a correct refusal takes milliseconds
N = ["nan", "inf", "-inf", "abc", "1e308"]  # bad for every numeric option
NEG = ["0", "-1"]
MAGIC = b"\x89MCAP0\r\n"
NUMPY_REPR = re.compile(r"\bnp\.[A-Za-z_]\w*|\barray\(")  # np.float64(0.0), np.True_, array([1.0])



# ------------------------------------------------------------------------------------------------ the case table
def opt_cases(cmd, base, option, values, prefix=()):
    """One case per bad value of ``option``; the error must name the option and the value."""
    return [(f"{' '.join(cmd)} {option} {v!r}", [*cmd, *prefix, *base, *_option(option, v)], 2, [option, v])
            for v in values]


def _option(option, value):
    """``--x=-inf``: argparse reads a separate '-inf' as an option, not a value (a negative number is fine)."""
    return [f"{option}={value}"] if value.startswith("-") and not value[1:2].isdigit() else [option, value]


def file_cases(cmd, base, option, names, needles=None):
    """One case per bad file given to ``option``; the error must name the file."""
    return [(f"{' '.join(cmd)} {option} <{n}>", [*cmd, *base, option, "{" + n + "}"], 2,
             ["{" + n + "}"] + list(needles or [])) for n in names]


CONFIG_FILES = ["missing", "directory", "binary", "bad_yaml", "list_yaml"]
PARAMS_TABLE_CASES = {  # params file: what its one line must name
    "params_tick": ["sim.tick_period", "-0.01", "[0.0001, 10] s"],
    "params_k": ["planner.k", "an odd integer in [1, 99]"],
    "params_period": ["safety_monitor.period", "-600", "[1, 86400] s"],
    "params_unknown_key": ["safety_monitor.perod", "no such parameter"],
    "params_samples": ["planner.mc_samples", "[1, 2000000]"],
    "params_stations": ["radar_od.stations", "a non-empty list of distinct station names"],
}
PROPAGATE = ["--roe", "0,100,0,0,0,0", "--model", "keplerian", "--days", "0.1"]
DEPLOY = ["--model", "linear", "--days", "1", "--inclinations", "97", "--dv", "1", "--angle-step", "90"]
RUN = ["--out", "{run_out}", "--params", "{params_unknown_node}"]  # a case accepted by mistake still starts nothing


def cases():
    c = []
    # design
    c += opt_cases(["design"], [], "--spl-dv", N + NEG)
    c += opt_cases(["design"], [], "--spl-dv", ["nan", "-1"], prefix=("--strategy", "multi_impulse"))
    c += opt_cases(["design"], [], "--u1", N + ["400"])
    c += opt_cases(["design"], [], "--strategy", ["bogus"])
    c += file_cases(["design"], [], "--config", CONFIG_FILES + ["scenario_nan", "scenario_range", "scenario_unknown",
                                                                "scenario_neg_density"])
    # mc
    mc = ["--samples", "10", "--p", "0.05"]
    c += opt_cases(["mc"], mc, "--samples", N + NEG + ["2.5", "20000000000"])
    c += opt_cases(["mc"], mc, "--seed", N + ["-1", "4294967296", "1.5"])
    c += opt_cases(["mc"], ["--samples", "10"], "--p", ["nan", "inf", "-0.1", "x", "", "0,nan", "2"])
    c += opt_cases(["mc"], mc, "--spl-dv", ["nan", "-1"])
    c += opt_cases(["mc"], mc, "--u1", ["inf"])
    c.append(("mc multi_impulse --p", ["mc", "--strategy", "multi_impulse", "--samples", "10", "--p", "0.05"], 2,
              ["--p"]))
    c += file_cases(["mc"], mc, "--config", CONFIG_FILES + ["scenario_nan", "scenario_samples0"])
    c.append(("mc --plots <file>", ["mc", *mc, "--plots", "{binary}"], 2, ["{binary}"]))
    # ops
    ops = ["--date", "2024-06-01", "--days", "0.2"]
    c += opt_cases(["ops"], ["--days", "0.2"], "--date", ["2024-13-01", "yesterday", "2060-01-01", "1800-01-01", ""])
    c += opt_cases(["ops"], ["--date", "2024-06-01"], "--days", N + NEG + ["8"])
    c += file_cases(["ops"], ops, "--tle", ["missing", "directory", "binary", "bad_tle", "decayed_tle"], ["--tle"])
    for line in (1, 2):  # a TLE line whose column 69 is not the modulo-10 checksum of the line
        c += file_cases(["ops"], ops, "--tle", [f"tle_line{line}_checksum"], ["--tle", f"line {line}", "checksum"])
    c += file_cases(["ops"], ops, "--tle", ["tle_short_line"], ["--tle", "line 2", "69"])
    c.append(("ops --tle 34 years before --date", ["ops", "--date", "2050-01-01", "--days", "0.2", "--tle", "{tle}"],
              2, ["--tle", "2050-01-01"]))
    c += file_cases(["ops"], ops, "--ops-config", CONFIG_FILES + ["ops_lat", "ops_step0", "ops_unknown", "ops_ltan",
                                                                  "ops_boresight"])
    c.append(("ops --plot <under a file>", ["ops", *ops, "--plot", "{binary}/x.png"], 2, ["{binary}"]))
    # run (never starts a node: the base arguments name an unknown node in --params)
    c += opt_cases(["run"], RUN, "--duration", N + NEG + ["3e6"])
    c += opt_cases(["run"], RUN, "--seed", N + ["-1"])
    c += opt_cases(["run"], RUN, "--timeout", N + NEG)
    c += file_cases(["run"], RUN, "--config", CONFIG_FILES + ["scenario_nan"])
    c += file_cases(["run"], ["--out", "{run_out}"], "--params", CONFIG_FILES + ["params_nan", "params_shape"])
    # a node parameter against its table, before any node starts: the node, the key and the rule
    for cmd, base in ((["run"], ["--out", "{run_out}"]), (["campaign"], ["--runs", "1", "--out", "{run_out}"])):
        for name, needles in PARAMS_TABLE_CASES.items():
            c += file_cases(cmd, base, "--params", [name], needles)
    # propagate
    c += opt_cases(["propagate"], PROPAGATE, "--roe", ["nan,0,0,0,0,0", "1,2,3", "a,b,c,d,e,f", "0,1e308,0,0,0,0",
                                                       ""])
    c.append(("propagate --roe beyond 1 % of a", ["propagate", *PROPAGATE, "--roe", "0,0,0,0,0,1e6"], 2,
              ["--roe", "1e+06"]))
    c += opt_cases(["propagate"], PROPAGATE, "--alt", N + NEG + ["100000", "2e6"])
    c += opt_cases(["propagate"], PROPAGATE, "--inc", N + ["0", "180", "-10"])
    c += opt_cases(["propagate"], PROPAGATE, "--u", N + ["1000"])
    c += opt_cases(["propagate"], PROPAGATE, "--days", N + NEG + ["31"])
    c += opt_cases(["propagate"], PROPAGATE, "--step", N + NEG + ["0.5"])
    c.append(("propagate --days 30 --step 1", ["propagate", *PROPAGATE, "--days", "30", "--step", "1"], 2,
              ["--step"]))
    c += opt_cases(["propagate"], PROPAGATE, "--model", ["bogus"])
    c += file_cases(["propagate"], PROPAGATE, "--config", ["missing", "bad_yaml", "scenario_nan"])
    # validate
    c += opt_cases(["validate"], [], "--days", ["0", "31", "nan", "1.5", "x", ""])
    c += opt_cases(["validate"], ["--days", "1"], "--mc", N + ["-1", "200000", "2.5"])
    c += opt_cases(["validate"], ["--days", "1", "--mc", "2"], "--p", ["nan", "-1", "5", "x"])
    c += opt_cases(["validate"], ["--days", "1", "--mc", "2"], "--seed", N + ["-1"])
    c.append(("validate --seed without --mc", ["validate", "--days", "1", "--seed", "3"], 2, ["--seed"]))
    c.append(("validate --p without --mc", ["validate", "--days", "1", "--p", "0.05"], 2, ["--p"]))
    c += file_cases(["validate"], ["--days", "1"], "--config", ["missing", "bad_yaml", "scenario_nan"])
    # deploy-sweep
    c += opt_cases(["deploy-sweep"], DEPLOY, "--altitude", N + NEG + ["50000"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--inclinations", ["nan", "0", "180", "-5", "x", ""])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--dv", ["nan", "0", "-1", "1e308", "x"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--angles", ["nan", "inf", "x", "1000"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--angle-step", N + NEG + ["200"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--days", N + NEG + ["61"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--step", N + NEG + ["0.5"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--density", N + ["-1"])
    c += opt_cases(["deploy-sweep"], DEPLOY, "--model", ["bogus"])
    c.append(("deploy-sweep --no-j2 nonlinear", ["deploy-sweep", *DEPLOY, "--model", "nonlinear", "--no-j2"], 2,
              ["j2"]))
    c.append(("deploy-sweep --plots <file>", ["deploy-sweep", *DEPLOY, "--plots", "{binary}"], 2, ["{binary}"]))
    # cluster
    cl = ["--samples", "0"]
    c += opt_cases(["cluster"], cl, "--sigma", N + NEG + ["100"])
    c += opt_cases(["cluster"], cl, "--p", N + ["0.4", "1", "-1"])
    c += opt_cases(["cluster"], cl, "--r-safe", N + NEG)
    c += opt_cases(["cluster"], cl, "--r-max", N + NEG)
    c.append(("cluster --r-max < --r-safe", ["cluster", *cl, "--r-safe", "10", "--r-max", "5"], 2, ["r_max", "5"]))
    c += opt_cases(["cluster"], [], "--samples", N + ["-1", "2000000", "1.5"])
    c += opt_cases(["cluster"], cl, "--seed", N + ["-1"])
    c += opt_cases(["cluster"], cl, "--method", ["bogus"])
    c += file_cases(["cluster"], cl, "--config", CONFIG_FILES + ["cluster_nan", "cluster_unknown", "cluster_negv",
                                                                 "cluster_nosats", "cluster_fast", "cluster_density"])
    # collision (a case accepted by mistake estimates from 10 brute-force samples)
    col = ["--hard-body-radius", "1", "--method", "mc", "--samples", "10", "--p", "0.05"]
    c += opt_cases(["collision"], col[2:], "--hard-body-radius", N + NEG + ["500"])
    c += opt_cases(["collision"], col, "--samples", N + NEG + ["2.5", "20000000000"])
    c += opt_cases(["collision"], col, "--seed", N + ["-1", "4294967296", "1.5"])
    c += opt_cases(["collision"], col, "--p", ["nan", "inf", "-0.1", "x", "", "2", "1e300"])
    c += opt_cases(["collision"], col, "--departure-distance", N + NEG + ["1e308"])
    c += opt_cases(["collision"], ["--hard-body-radius", "1", "--samples", "10", "--p", "0.05"], "--ce-samples",
                   N + NEG + ["99", "2.5", "20000000000"])
    c.append(("collision is: no sample back from the departure distance",
              ["collision", "--hard-body-radius", "1", "--samples", "100", "--ce-samples", "100", "--p", "0.05",
               "--departure-distance", "1e7"], 2, ["departure distance", "1e+07"]))
    c += opt_cases(["collision"], col, "--method", ["bogus"])
    c += opt_cases(["collision"], col, "--chunk-size", N + NEG + ["100"])
    c += opt_cases(["collision"], col, "--workers", ["0", "257", "x"])
    c += file_cases(["collision"], col, "--config", CONFIG_FILES + ["scenario_nan"])
    # export (the reference bag; a case accepted by mistake writes a set into a temporary directory)
    exp = ["{reference_bag}", "--out", "{out}"]
    for name in ("missing", "empty_dir", "garbage_bag", "magic_only", "truncated_bag"):
        c.append((f"export <{name}>", ["export", "{" + name + "}", "--out", "{out}"], 2, ["{" + name + "}"]))
    c += opt_cases(["export"], exp, "--format", ["json"])
    c += opt_cases(["export"], exp, "--epoch-utc", ["July", "", "2016-13-01T00:00:00", "nan"])
    c += opt_cases(["export"], exp, "--carrier-isp", N + NEG)
    c += file_cases(["export"], exp, "--config", CONFIG_FILES + ["scenario_nan"])
    c.append(("export --out <a file>", ["export", "{reference_bag}", "--out", "{binary}"], 2, ["{binary}"]))
    c.append(("export --out <under a file>", ["export", "{reference_bag}", "--out", "{binary}/x"], 2, ["{binary}"]))
    # od (the offline OD; a case accepted by mistake stops at the missing TDM, whose message names no option)
    od = ["--tdm", "{missing}", "--carrier-oem", "{missing}"]
    c.append(("od --tdm <missing>", ["od", *od], 2, ["{missing}"]))
    c.append(("od --tdm <binary>", ["od", "--tdm", "{binary}", "--carrier-oem", "{binary}"], 2, ["{binary}"]))
    c.append(("od --tdm <a bag>", ["od", "--tdm", "{garbage_bag}", "--carrier-oem", "{binary}"], 2,
              ["{garbage_bag}"]))
    c.append(("od without --carrier-oem", ["od", "--tdm", "{bad_yaml}"], 2, ["--carrier-oem"]))
    c += opt_cases(["od"], od, "--since", ["July", "", "2016-13-01T00:00:00"])
    c += opt_cases(["od"], od, "--until", ["July", "nan"])
    c += opt_cases(["od"], od, "--station", ["TIRA", "TIRA,95,0,0", "TIRA,50,nan,0", ",50,7,300"])
    c += opt_cases(["od"], od, "--sigma-range", N + NEG)
    c += opt_cases(["od"], od, "--sigma-angle", N + NEG + ["1"])
    c += opt_cases(["od"], od, "--min-pass", N + NEG + ["2.5"])
    c += opt_cases(["od"], od, "--min-passes", N + NEG)
    c += opt_cases(["od"], od, "--edit-p", N + NEG + ["0.6"])
    c += opt_cases(["od"], od, "--predict", N + NEG + ["1000"])
    c += opt_cases(["od"], od, "--format", ["json"])
    # campaign (--out holds a campaign of other settings: a case accepted by mistake is refused before any run)
    camp = ["--runs", "2", "--out", "{campaign_other}"]
    c += opt_cases(["campaign"], camp, "--runs", N + NEG + ["2.5", "100001"])
    c += opt_cases(["campaign"], camp, "--seed", N + ["-1", "4294967296", "1.5"])
    c.append(("campaign last seed beyond 2**32 - 1", ["campaign", *camp, "--seed", "4294967295"], 2,
              ["--seed", "4294967295", "last seed"]))
    c += opt_cases(["campaign"], camp, "--workers", ["0", "257", "x"])
    c += opt_cases(["campaign"], camp, "--scheduler", ["localhost:8786", ""])
    c.append(("campaign --workers with --scheduler", ["campaign", *camp, "--workers", "2", "--scheduler",
                                                      "tcp://127.0.0.1:1"], 2, ["--scheduler", "not allowed with"]))
    c += opt_cases(["campaign"], camp, "--duration", N + NEG + ["3e6"])
    c += opt_cases(["campaign"], camp, "--timeout", N + NEG + ["1e6"])
    c += opt_cases(["campaign"], camp, "--domains", ["5-3", "x", "0-200", "7"])
    c += opt_cases(["campaign"], camp, "--open-loop-samples", N + ["99", "20000000", "2.5"])
    c += file_cases(["campaign"], camp, "--config", CONFIG_FILES + ["scenario_nan"])
    c += file_cases(["campaign"], camp, "--params", CONFIG_FILES + ["params_nan", "params_shape"])
    c.append(("campaign --out <under a file>", ["campaign", "--runs", "1", "--out", "{binary}/c"], 2, ["{binary}"]))
    # bag info: unreadable -> 2, damaged -> 1 with the damage named
    for name in ("missing", "empty_dir", "garbage_bag", "empty_file"):
        c.append((f"bag info <{name}>", ["bag", "info", "{" + name + "}"], 2, ["{" + name + "}"]))
    for name in ("magic_only", "truncated_bag", "huge_record_bag", "crc_bag", "bad_metadata_bag"):
        c.append((f"bag info <{name}>", ["bag", "info", "{" + name + "}"], 1, ["PROBLEM"]))
        c.append((f"bag info --json <{name}>", ["bag", "info", "--json", "{" + name + "}"], 1, ['"problems"']))
    # bag recover: nothing recoverable -> 2; cut off -> 0; corrupt inside -> 1; all say what was lost
    for name in ("missing", "garbage_bag", "empty_file", "magic_only"):
        c.append((f"bag recover <{name}>", ["bag", "recover", "{" + name + "}", "{out}"], 2, ["{" + name + "}"]))
    c.append(("bag recover <truncated_bag>", ["bag", "recover", "{truncated_bag}", "{out}"], 0, ["cut off", "lost"]))
    c.append(("bag recover <huge_record_bag>", ["bag", "recover", "{huge_record_bag}", "{out}"], 1, ["CORRUPT"]))
    c.append(("bag recover <crc_bag>", ["bag", "recover", "{crc_bag}", "{out}"], 1, ["CORRUPT"]))
    c.append(("bag recover <bad_metadata_bag>", ["bag", "recover", "{bad_metadata_bag}", "{out}"], 0,
              ["metadata.yaml"]))
    c.append(("bag recover into a non-empty dir", ["bag", "recover", "{good_bag}", "{run_out}"], 2, ["{run_out}"]))
    c.append(("bag recover without OUT", ["bag", "recover", "{good_bag}"], 2, ["out"]))
    # replay: refused at once, before any DDS traffic
    c += opt_cases(["replay"], ["{good_bag}"], "--rate", N + NEG + ["1e-300"])
    c += opt_cases(["replay"], ["{good_bag}"], "--clock", N + ["0", "1e-300"])
    c += opt_cases(["replay"], ["{good_bag}"], "--delay", N + ["-1", "1e300"])
    c += opt_cases(["replay"], ["{good_bag}"], "--linger", N + ["-1", "1e300"])
    c += opt_cases(["replay"], ["{good_bag}"], "--topics", ["/not/there", "bad topic!"])
    for name in ("missing", "garbage_bag", "magic_only", "truncated_bag", "huge_record_bag", "crc_bag"):
        c.append((f"replay <{name}>", ["replay", "{" + name + "}"], 2, ["{" + name + "}"]))
    return c


CASES = cases()


# ------------------------------------------------------------------------------------------------ the fixtures
def _cdr_string(text: str) -> bytes:
    """A std_msgs/msg/String in CDR (little endian): encapsulation header, length with NUL, bytes, NUL."""
    data = text.encode() + b"\0"
    return b"\x00\x01\x00\x00" + struct.pack("<I", len(data)) + data


def _records(data: bytes):
    """(offset, opcode, length) of every top-level record of a complete MCAP file."""
    off = len(MAGIC)
    while off + 9 <= len(data) - len(MAGIC):
        opcode, length = struct.unpack_from("<BQ", data, off)
        yield off, opcode, length
        off += 9 + length


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from roe_sep.bag import qos
    from roe_sep.bag.writer import BagWriter

    d = tmp_path_factory.mktemp("bad_input")
    f = {"missing": d / "missing.yaml", "directory": d, "run_out": d / "run_out", "empty_dir": d / "empty_dir"}
    f["run_out"].mkdir()
    (f["run_out"] / "keep.txt").write_text("not empty")
    f["empty_dir"].mkdir()

    def text(name, content):
        f[name] = d / f"{name}.yaml"
        f[name].write_text(content)

    f["binary"] = d / "binary.yaml"
    f["binary"].write_bytes(b"\xff\xfe\x00\x9c binary garbage \x00\x01")
    text("bad_yaml", "separation: [unclosed\n  - x: {\n")
    text("list_yaml", "- 1\n- 2\n")
    text("scenario_nan", "separation: {spl_dv: .nan}\n")
    text("scenario_range", "separation: {altitude: 1.0}\n")
    text("scenario_unknown", "separation: {spl_dvv: 1.0}\n")
    text("scenario_neg_density", "monte_carlo: {density: -1.0e-12}\n")
    text("scenario_samples0", "monte_carlo: {samples: 0}\n")
    ops = (ROOT / "config" / "ops.yaml").read_text()
    text("ops_lat", ops.replace("lat_deg: 50.617", "lat_deg: 95.0"))
    text("ops_step0", ops.replace("time_step_s: 20.0", "time_step_s: 0"))
    text("ops_unknown", ops.replace("time_step_s: 20.0", "time_step: 20.0"))
    text("ops_ltan", ops.replace("ltan_h: 21.5", "ltan_h: .inf"))
    text("ops_boresight", ops.replace("boresight_rtn: ejection", "boresight_rtn: [0, 0, 0]"))
    f["bad_tle"] = d / "bad.tle"
    f["bad_tle"].write_text("1 garbage line that is no element set\n2 and neither is this one\n")
    line1 = "1 41604U 16040F   16183.50000000  .00000500  00000-0  25000-4 0  9996"  # 6: its checksum
    line2 = "2 41604  97.4500 250.0000 0010000  90.0000 270.0000 15.18000000  1004"
    f["tle"] = d / "biros.tle"
    f["tle"].write_text(f"{line1}\n{line2}\n")
    f["decayed_tle"] = d / "decayed.tle"  # a period of 80 min: perigee below the surface
    f["decayed_tle"].write_text(f"{line1}\n{line2.replace('15.18000000  1004', '17.90000000  1006')}\n")
    f["tle_line1_checksum"] = d / "line1_checksum.tle"
    f["tle_line1_checksum"].write_text(f"{line1[:-1]}7\n{line2}\n")
    f["tle_line2_checksum"] = d / "line2_checksum.tle"
    f["tle_line2_checksum"].write_text(f"BIROS\n{line1}\n{line2[:-1]}5\n")
    f["tle_short_line"] = d / "short_line.tle"
    f["tle_short_line"].write_text(f"{line1}\n{line2[:-1]}\n")
    cluster = (ROOT / "config" / "cluster.yaml").read_text()
    text("cluster_nan", cluster + "\nsigma_deg_s: .nan\n" if "sigma_deg_s" not in cluster else
         cluster.replace("sigma_deg_s:", "sigma_deg_s: .nan #"))
    text("cluster_unknown", "sigmaa_deg_s: 0.3\n")
    text("cluster_negv", "sats: [{name: a, velocity: -1.0, delta_q: 0.006}]\n")
    text("cluster_nosats", "sats: []\n")
    text("cluster_fast", "sats: [{name: a, velocity: 1.0e+300, delta_q: 0.006}]\n")
    text("cluster_density", "density: 1.0\n")
    text("cluster_small", "max_delay: 15.0\ndelay_step: 5.0\nturns: 0.5\ntime_step: 60.0\n")
    f["reference_bag"] = ROOT / "bags" / "default_run"
    f["campaign_other"] = d / "campaign_other"
    f["campaign_other"].mkdir()
    (f["campaign_other"] / "campaign.json").write_text(json.dumps({"scenario_sha256": "0" * 64, "overrides": {},
                                                                   "duration": 1.0}))
    text("params_unknown_node", "no_such_node: {ros__parameters: {x: 1}}\n")
    text("params_nan", "sim: {ros__parameters: {tick_period: .nan}}\n")
    text("params_shape", "sim: [1, 2]\n")
    text("params_tick", "sim: {ros__parameters: {tick_period: -0.01}}\n")
    text("params_k", "planner: {ros__parameters: {k: 2}}\n")
    text("params_period", "safety_monitor: {ros__parameters: {period: -600}}\n")
    text("params_unknown_key", "safety_monitor: {ros__parameters: {perod: 600.0}}\n")
    text("params_samples", "planner: {ros__parameters: {mc_samples: 1000000000}}\n")
    text("params_stations", "radar_od: {ros__parameters: {stations: ['TIRA', 'TIRA']}}\n")

    # bags: a good one, then damaged copies of its file
    good = d / "good_bag"
    w = BagWriter(good, chunk_size=512)
    w.add_topic("/chatter", "std_msgs/msg/String", [qos.profile_dict()], definition="string data\n")
    for i in range(60):
        w.write("/chatter", _cdr_string(f"message {i}"), 1_000_000_000 + i * 10_000_000)
    w.close()
    f["good_bag"] = good
    data = (good / w.file_name).read_bytes()

    def bag_file(name, content):
        f[name] = d / f"{name}.mcap"
        f[name].write_bytes(content)

    bag_file("garbage_bag", b"this is not a bag " * 20)
    bag_file("empty_file", b"")
    bag_file("magic_only", MAGIC)
    bag_file("truncated_bag", data[: len(data) * 2 // 3])
    chunks = [(o, n) for o, op, n in _records(data) if op == 0x06]
    assert len(chunks) >= 4
    middle = chunks[len(chunks) // 2]  # damage in the middle: the chunks before it are recoverable
    huge = bytearray(data)
    huge[middle[0] + 1: middle[0] + 9] = struct.pack("<Q", 1 << 62)  # its length field claims 2**62 bytes
    bag_file("huge_record_bag", bytes(huge))
    crc = bytearray(data)
    crc[middle[0] + 9 + middle[1] - 5] ^= 0xFF  # a byte of its last message: the chunk CRC fails
    bag_file("crc_bag", bytes(crc))
    bad_meta = d / "bad_metadata_bag"
    shutil.copytree(good, bad_meta)
    (bad_meta / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed\n")
    f["bad_metadata_bag"] = bad_meta
    return {k: str(v) for k, v in f.items()}


def _fill(item: str, files: dict, out: str) -> str:
    for k, v in files.items():
        item = item.replace("{" + k + "}", v)
    return item.replace("{out}", out)


class _Hang(BaseException):  # not an Exception: main's last-resort handler must not swallow it
    pass


def run_in_process(argv, capsys):
    """(exit status or 'traceback'/'hang', stdout, stderr, exception) of ``roe-sep argv``."""
    def alarm(*_):
        raise _Hang

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(TIMEOUT_S)
    exc = None
    try:
        code = main(argv)
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else (0 if e.code is None else 2)
    except _Hang:
        code = "hang"
    except BaseException as e:  # noqa: BLE001  (what a user would see as a traceback)
        code, exc = "traceback", e
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    out = capsys.readouterr()
    return code, out.out, out.err, exc


def classify(code, out, err, expect, needles):
    if code in ("traceback", "hang"):
        return code
    if code == 3 or "Traceback (most recent call last)" in err:
        return "traceback"
    if code == 0 and expect != 0:
        return "silent"
    if NUMPY_REPR.search(out + err):
        return "numpy"
    if code != expect:
        return "wrong"
    if expect == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if len(lines) != 1:
            return "multiline"
        if not all(n.lower() in lines[0].lower() for n in needles if n):
            return "wrong"
        return "ok"
    return "ok" if all(n in out + err for n in needles) else "wrong"


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input(case, files, capsys, tmp_path):
    name, argv, expect, needles = case
    out_dir = str(tmp_path / "recovered")
    argv = [_fill(a, files, out_dir) for a in argv]
    needles = [_fill(n, files, out_dir) for n in needles]
    code, out, err, exc = run_in_process(argv, capsys)
    verdict = classify(code, out, err, expect, needles)
    assert verdict == "ok", (f"{name}: {verdict} (exit {code}, expected {expect}; needles {needles})\n"
                             f"stderr: {err[-2000:]}\nstdout: {out[-500:]}\nexception: {exc!r}")
    assert not (code == 0 and ("NaN" in out or "Infinity" in out)), f"{name}: non-strict JSON on exit 0:\n{out[-500:]}"


def test_console_script_refuses_in_one_line():
    """The real process (argparse exits, not main's return): one line, exit 2, and replay refuses at once."""
    for argv in (["design", "--spl-dv", "nan"], ["replay", str(ROOT / "bags" / "default_run"), "--rate", "1e-300"]):
        proc = subprocess.run([sys.executable, "-m", "roe_sep.cli", *argv], capture_output=True, text=True,
                              timeout=60, cwd=ROOT)
        assert proc.returncode == 2, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1 and argv[-2] in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr


def subcommands():
    """The names of ``roe-sep``'s subcommands, from its parser."""
    import argparse

    from roe_sep.cli import build_parser

    return {name for action in build_parser()._actions if isinstance(action, argparse._SubParsersAction)
            for name in action.choices}


def test_the_table_covers_every_subcommand_as_the_docs_say():
    """Every subcommand has bad inputs, and every count of them the docs quote ("553 bad inputs", "| 553 cases")
    is the table's."""
    per_command = collections.Counter(argv[0] for _, argv, _, _ in CASES)
    assert subcommands() - set(per_command) == set(), "subcommands without a bad input"
    quoted = {path.name: [int(n) for n in re.findall(r"\b(\d+) (?:bad (?:command-line )?inputs|cases\b)",
                                                     path.read_text(encoding="utf-8"))]
              for path in (ROOT / "docs" / "failures.md", ROOT / "Makefile")}
    assert {name: [n for n in counts if n != len(CASES)] for name, counts in quoted.items()} == {
        name: [] for name in quoted}, f"the table has {len(CASES)} cases"


# ------------------------------------------------------------------------------------------------ strict JSON
def _refuse(name):
    raise ValueError(f"non-strict JSON constant {name}")


JSON_COMMANDS = [
    ["design", "--json"],
    ["design", "--strategy", "multi_impulse", "--json"],
    ["mc", "--samples", "200", "--p", "0,0.05", "--json"],
    ["mc", "--samples", "1", "--seed", "614", "--p", "0.05", "--json"],  # the one sample has f1 < 0.7: an infinity
    ["mc", "--strategy", "multi_impulse", "--samples", "50", "--json"],
    ["ops", "--date", "2024-06-01", "--days", "0.5", "--json"],
    ["propagate", *PROPAGATE, "--json"],
    ["validate", "--days", "1", "--json"],
    ["validate", "--days", "1", "--mc", "2", "--p", "0.05", "--json"],
    ["deploy-sweep", *DEPLOY, "--json"],
    ["cluster", "--config", "{cluster_small}", "--samples", "20", "--json"],
    ["bag", "info", "--json", "{good_bag}"],
    ["bag", "info", "--json", "{truncated_bag}"],
]


@pytest.mark.parametrize("argv", JSON_COMMANDS, ids=[" ".join(a[:3]) for a in JSON_COMMANDS])
def test_json_output_is_strict(argv, files, capsys):
    argv = [_fill(a, files, "") for a in argv]
    code, out, err, exc = run_in_process(argv, capsys)
    assert code in (0, 1), (code, err, exc)
    rep = json.loads(out, parse_constant=_refuse)
    if argv[:2] == ["mc", "--samples"] and "614" in argv:
        assert rep["crossing_min_within_3sigma_f1"] is None  # no sample there: null, never Infinity
