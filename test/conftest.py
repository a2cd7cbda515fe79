import os

# DDS traffic stays on this machine in every test session (see scripts/test.sh for the domain id).
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
