"""Ground-control station for a rigid team of rotorcraft carrying one payload."""
