"""OpenSim models (``.osim``) on Pinocchio."""
