"""The formation's maths: the graph, the desired shape, rigidity and motions.

Pure functions and frozen values over arrays, as in the paper's section III;
no I/O and no configuration.

Modules:

    ``_graph``   Rigid formation model: graph, desired shape, incidence and rigidity.
    ``_motion``  Rigid motions of the team synthesised as distance disagreements.
"""

from gcs.formation._graph import (
    Formation,
    FormationError,
    build_formation,
    incidence_matrix,
    is_infinitesimally_rigid,
    realize_positions,
    rigidity_matrix,
)
from gcs.formation._motion import (
    MotionBasis,
    centripetal_matrix,
    edges_to_slots,
    local_pseudoinverse,
    motion_basis,
)

__all__ = [
    "Formation",
    "FormationError",
    "MotionBasis",
    "build_formation",
    "centripetal_matrix",
    "edges_to_slots",
    "incidence_matrix",
    "is_infinitesimally_rigid",
    "local_pseudoinverse",
    "motion_basis",
    "realize_positions",
    "rigidity_matrix",
]
