"""``roe-sep export BAG --out DIR [--format xml|kvn]``: the CCSDS navigation data messages of a recorded run
(OPM per approved plan and of the executed carrier burns, OEM, TDM, CDM; :mod:`roe_sep.ndm.dataset`)."""

from pathlib import Path

import yaml

from ..bag.reader import resolve
from ..core.config import load_scenario
from ..errors import BagError
from ..ndm import frames
from ..ndm.options import FORMATS, TOPICS, Options, RunMessages  # light: the NDM library loads when a set is written
from .common import emit, finite_float

ISP_MAX = 1e5  # s: beyond any thruster flown (ion engines reach ~1e4 s); a larger one makes the OPM's mass change 0


def read_run(bag) -> RunMessages:
    """The set's topics of a bag (directory or .mcap file), decoded with the bag's own schemas."""
    from mcap_ros2.reader import read_ros2_messages

    _, file = resolve(bag)
    run = RunMessages()
    try:
        for m in read_ros2_messages(str(file), topics=list(TOPICS)):
            run.add(m.channel.topic, m.ros_msg)
    except Exception as exc:  # noqa: BLE001  (a truncated or foreign file)
        raise BagError(f"{bag}: cannot read messages ({exc.__class__.__name__}: {exc}); a recording that did not "
                       "finish needs `roe-sep bag recover` first") from None
    return run


def run_parameters(bag):
    """``(epoch_utc, scenario_file, source)`` of the run: the simulator's ``epoch_utc`` and the scenario file from
    the run's ``params.yaml`` next to the bag directory (``roe-sep run`` writes OUT/params.yaml beside OUT/bag),
    else the defaults (source ``default``)."""
    bag_dir, file = resolve(bag)
    params = Path(bag_dir or file.parent).resolve().parent / "params.yaml"
    epoch, scenario = None, None
    if params.is_file():
        try:
            data = yaml.safe_load(params.read_text(encoding="utf-8")) or {}
            shared = data.get("/**", {}).get("ros__parameters", {})
            sim = data.get("sim", {}).get("ros__parameters", {})
            epoch = sim.get("epoch_utc") or shared.get("epoch_utc")
            scenario = sim.get("scenario_file") or shared.get("scenario_file")
        except (yaml.YAMLError, AttributeError):
            pass
    return (str(epoch) if epoch else Options().epoch_utc, scenario or None,
            str(params) if (epoch or scenario) else "default")


def cmd_export(args):
    try:
        epoch, scenario_file, source = run_parameters(args.bag)
    except BagError as exc:
        raise ValueError(str(exc)) from None
    if args.epoch_utc is not None:  # given, even empty: checked, never silently the run's
        epoch, source = args.epoch_utc, "--epoch-utc"
    try:
        frames.parse_epoch(epoch)
    except ValueError as exc:
        raise ValueError(f"--epoch-utc: {exc}") from None
    carrier = load_scenario(args.config or scenario_file).monte_carlo.carrier
    opts = Options(epoch_utc=epoch, carrier_mass=carrier.mass, carrier_drag_area=carrier.area,
                   carrier_drag_coeff=carrier.cd, carrier_isp=args.carrier_isp)
    from ..ndm.dataset import write_set

    try:
        paths = write_set(read_run(args.bag), args.out, args.format, opts)
    except BagError as exc:
        raise ValueError(str(exc)) from None
    rep = {"bag": str(args.bag), "out": str(args.out), "format": args.format, "epoch_utc": epoch,
           "epoch_source": source, "frame": frames.INERTIAL_FRAME, "time_system": frames.TIME_SYSTEM,
           "files": [str(p) for p in paths]}

    def human(r):
        print(f"CCSDS NDM set of {r['bag']} ({r['format']}, {r['frame']}, {r['time_system']} from "
              f"{r['epoch_utc']}, {r['epoch_source']})")
        for f in r["files"]:
            print(f"  {f}")

    emit(rep, args.json, human)
    return 0 if paths else 1


def register(subparsers):
    p = subparsers.add_parser("export", help="CCSDS OPM/OEM/TDM/CDM files of a recorded run")
    p.add_argument("bag", help="bag directory or .mcap file")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--format", choices=FORMATS, default="xml", help="NDM/XML (default) or KVN")
    p.add_argument("--epoch-utc", default=None,
                   help="ISO-8601 UTC epoch of sim time 0 (default: the run's params.yaml, else 2016-07-01T00:00:00)")
    p.add_argument("--config", default=None, help="scenario YAML for the carrier's mass and drag parameters "
                   "(default: the run's, else the embedded default)")
    p.add_argument("--carrier-isp", type=finite_float(0.0, ISP_MAX, lo_open=True, unit="s"),
                   default=Options.carrier_isp,
                   help=f"s, carrier thruster specific impulse for MAN_DELTA_MASS, at most {ISP_MAX:g} (default 60)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_export)
