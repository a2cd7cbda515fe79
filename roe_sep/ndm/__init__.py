"""CCSDS Navigation Data Messages (OPM, OEM, TDM, CDM) of a run, for ground segments:
:mod:`roe_sep.ndm.frames` (time scales, EME2000, RTN <-> inertial), :mod:`roe_sep.ndm.messages` (building and
reading them with the ``ccsds-ndm`` library, atomic files), :mod:`roe_sep.ndm.dataset` (the set of a run from its
decoded messages). No ROS: a bag, the ``ground_bridge`` node and tests all feed it the same message objects."""
