#!/usr/bin/env python3
"""DDS smoke test of the venv: a latched roe_sep_msgs/ManeuverPlan round trip.

Two rclpy nodes in one process. The publisher (RELIABLE, TRANSIENT_LOCAL, depth 1) publishes
first; the subscriber is created only afterwards and must still get the plan (latching).
Refuses to run unless discovery is limited to localhost and ROS_DOMAIN_ID is set:
    ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID=57 .venv/bin/python scripts/smoke_dds.py
"""
import os
import sys
import time

if os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE') != 'LOCALHOST' or not os.environ.get('ROS_DOMAIN_ID'):
    sys.exit('set ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and ROS_DOMAIN_ID first')

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from roe_sep_msgs.msg import ImpulsiveManeuver, ManeuverPlan  # noqa: E402

TOPIC = '/roe_sep/smoke/maneuver_plan'


def main() -> int:
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    rclpy.init()
    try:
        pub_node = rclpy.create_node('smoke_plan_pub')
        pub = pub_node.create_publisher(ManeuverPlan, TOPIC, qos)
        plan = ManeuverPlan()
        plan.header.stamp.sec = 1234
        plan.header.frame_id = 'rtn'
        plan.strategy = 'double_impulse'
        plan.ejection_epoch.sec = 1000
        for i, (dt, purpose) in enumerate(((0.012, 'drift_stop'), (-0.004, 'drift_reduction'))):
            m = ImpulsiveManeuver()
            m.epoch.sec = 2000 + 100 * i
            m.mean_arg_latitude = 0.5 + i
            m.dv_rtn.y = dt
            m.spacecraft = 'carrier'
            m.purpose = purpose
            plan.maneuvers.append(m)
        plan.aimed.a_dl = -150.0
        plan.aimed.covariance[0] = 4.0
        plan.aimed.chief.semi_major_axis = 6_878_137.0
        plan.p_reduction = 0.004
        pub.publish(plan)

        got = []
        sub_node = rclpy.create_node('smoke_plan_sub')  # created AFTER publish: latched delivery
        sub_node.create_subscription(ManeuverPlan, TOPIC, got.append, qos)
        ex = SingleThreadedExecutor()
        ex.add_node(pub_node)
        ex.add_node(sub_node)
        t0 = time.monotonic()
        while not got and time.monotonic() - t0 < 20.0:
            ex.spin_once(timeout_sec=0.1)
        if not got:
            print('FAIL: no ManeuverPlan received within 20 s')
            return 1
        r = got[0]
        ok = (r.strategy == plan.strategy and len(r.maneuvers) == 2
              and r.maneuvers[1].purpose == 'drift_reduction' and r.maneuvers[0].dv_rtn.y == 0.012
              and r.aimed.a_dl == -150.0 and r.aimed.covariance[0] == 4.0
              and r.aimed.chief.semi_major_axis == 6_878_137.0 and r.p_reduction == 0.004
              and r.ejection_epoch.sec == 1000)
        print('%s: latched ManeuverPlan round trip in %.2f s (domain %s, %s)' % (
            'ok' if ok else 'FAIL (content mismatch)', time.monotonic() - t0,
            os.environ['ROS_DOMAIN_ID'], rclpy.utilities.get_rmw_implementation_identifier()))
        ex.shutdown()
        sub_node.destroy_node()
        pub_node.destroy_node()
        return 0 if ok else 1
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    sys.exit(main())
