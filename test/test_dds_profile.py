"""The Fast DDS profile of a run's node processes (roe_sep.graph.dds_profile): valid XML that Fast DDS loads without
an error, with the heartbeat period of roe_sep.graph; a user's own profile, or another RMW, is left alone."""

import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from roe_sep.graph import DDS_HEARTBEAT_PERIOD, DDS_PROFILE_ENV, dds_environment, dds_profile

NS = {"d": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}


def test_the_profile_sets_the_heartbeat_period_of_the_default_writer():
    root = ET.fromstring(dds_profile().encode())
    (writer,) = root.findall("d:profiles/d:data_writer", NS)
    assert writer.get("is_default_profile") == "true"
    period = writer.find("d:times/d:heartbeatPeriod", NS)
    assert int(period.find("d:sec", NS).text) + int(period.find("d:nanosec", NS).text) * 1e-9 == DDS_HEARTBEAT_PERIOD


def test_the_environment_names_the_written_profile(tmp_path):
    env = dds_environment(tmp_path, {})
    assert env == {DDS_PROFILE_ENV[0]: str((tmp_path / "fastdds.xml").resolve())}
    assert (tmp_path / "fastdds.xml").read_text() == dds_profile()


@pytest.mark.parametrize("env", [{"FASTRTPS_DEFAULT_PROFILES_FILE": "/x.xml"},
                                 {"FASTDDS_DEFAULT_PROFILES_FILE": "/x.xml"},
                                 {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}])
def test_a_users_profile_or_another_rmw_is_left_alone(tmp_path, env):
    assert dds_environment(tmp_path, env) == {}
    assert not (tmp_path / "fastdds.xml").exists()


@pytest.mark.dds
def test_fast_dds_loads_the_profile_without_an_error(tmp_path):
    pytest.importorskip("rclpy")
    from rosutil import ros_env

    env = dict(ros_env(), **dds_environment(tmp_path, {}))
    code = ("import rclpy; from std_msgs.msg import String; rclpy.init(); n = rclpy.create_node('dds_profile_test');"
            "n.create_publisher(String, '/dds_profile_test', 10); print('ok'); rclpy.shutdown()")
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr
    assert "XMLPARSER" not in done.stderr and "Error" not in done.stderr, done.stderr
