"""CCSDS Navigation Data Messages (OPM, OEM, TDM, CDM) of a run, for ground segments: :mod:`.frames` (time scales,
EME2000, RTN <-> inertial), :mod:`.messages` (building and reading them with the ``ccsds-ndm`` library, atomic
files), :mod:`.dataset` (the set of a run from its decoded messages). No ROS: a bag, the ``ground_bridge`` node and
tests all feed it the same message objects."""
