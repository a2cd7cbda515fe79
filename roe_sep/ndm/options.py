"""What the CCSDS set of a run is made from, without the NDM library (whose import takes seconds): the options the
messages do not carry, the topics and the messages received (:mod:`.dataset` builds the set from them)."""

from dataclasses import dataclass, field

from .. import interfaces
from ..core.od.radar import DEFAULT_EPOCH_UTC

FORMATS = ("xml", "kvn")
TOPICS = (interfaces.TRUTH_ROE_TOPIC, interfaces.EJECTION_TOPIC, interfaces.DRIFT_STOP_PLAN_TOPIC,
          interfaces.ACQUISITION_PLAN_TOPIC, interfaces.PLAN_CHECK_TOPIC, interfaces.EXECUTED_TOPIC,
          interfaces.OD_TOPIC, interfaces.RADAR_TOPIC)
"""Topics the set is made from."""


@dataclass
class Options:
    """What the messages do not carry.

    The calendar epoch of sim time 0; object names/ids; the carrier's mass [kg], drag area [m^2] and coefficient
    (the scenario's ``monte_carlo.carrier``) and the specific impulse [s] of its thrusters (OPM MAN_DELTA_MASS by
    the rocket equation; the seeds give none: 60 s, a cold-gas value, is an assumption; the mass change scales
    about as 1/Isp: 0.32 kg for the 1.36 m/s drift-stop at 140 kg); the OEM step of the OD estimate's ephemeris
    [s] and the smallest spacing of the truth states in the OEM [s] (the simulator's 60 s truth thinned: 8-point
    Lagrange interpolation over 300 s steps is good to centimeters on a 95-min orbit, and the XML OEM of a whole
    run is 5x smaller and faster to write); the closest-approach search (departure distance [m], sampling step
    [s]).
    """

    epoch_utc: str = DEFAULT_EPOCH_UTC
    carrier_name: str = "CARRIER"
    picosat_name: str = "PICOSATELLITE"
    carrier_mass: float = 140.0
    carrier_drag_area: float = 0.48
    carrier_drag_coeff: float = 2.3
    carrier_isp: float = 60.0
    od_step: float = 300.0
    oem_step: float = 300.0
    departure_distance: float = 1000.0
    ca_step: float = 1.0


@dataclass
class RunMessages:
    """Messages of a run by topic (lists in arrival order)."""

    by_topic: dict = field(default_factory=lambda: {t: [] for t in TOPICS})

    def add(self, topic, msg):
        self.by_topic.setdefault(topic, []).append(msg)

    def __getitem__(self, topic):
        return self.by_topic.get(topic, [])
