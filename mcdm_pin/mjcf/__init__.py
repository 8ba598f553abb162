"""Pinocchio models read from MuJoCo's compiled models (MJCF, MyoSuite)."""
