"""The guidance law (eq. udi of the paper), per vehicle, from relative data.

:class:`Guidance` turns relative positions, own velocities and a motion demand
into one acceleration per vehicle; the compiled arithmetic is in ``_udi``.

Modules:

    ``_law``        Formation-motion guidance: eq. udi of the paper, per vehicle, from
                    relative data.
    ``_rope_lead``  The rope's pull turning with a spinning team, or growing as the ropes
                    take the payload, led by the autopilot's lag.
    ``_udi``  The guidance's per-vehicle arithmetic, compiled: eq. udi and its local frames
              as loops.
"""

from gcs.guidance._law import Guidance, MotionDemand, saturate
from gcs.guidance._rope_lead import rope_growth_lead, rope_pull_ned, rope_turn_lead
from gcs.guidance._udi import finite_max_norm

__all__ = [
    "Guidance",
    "MotionDemand",
    "finite_max_norm",
    "rope_growth_lead",
    "rope_pull_ned",
    "rope_turn_lead",
    "saturate",
]
