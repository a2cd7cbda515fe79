"""rclpy nodes: parameters, QoS, callbacks and message conversion only; the physics lives in :mod:`roe_sep.core`."""
