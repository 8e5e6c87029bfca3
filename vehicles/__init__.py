"""Onboard autopilot of a simulated rotorcraft: INDI control, modes, MAVLink endpoint."""
