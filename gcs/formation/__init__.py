"""The formation's maths: the graph, the desired shape, rigidity and motions.

Pure functions and frozen values over arrays, as in the paper's section III;
no I/O and no configuration.

Modules:

    ``_graph``   Rigid formation model: graph, desired shape, incidence and rigidity.
    ``_motion``  Rigid motions of the team synthesised as distance disagreements.
    ``_fit``     The desired shape fitted rigidly onto the team: its heading, its ghost.
"""

from gcs.formation._fit import fit_rotation, fit_shape
from gcs.formation._graph import Formation, FormationError, build_formation, rigidity_matrix
from gcs.formation._motion import MotionBasis, motion_basis

__all__ = [
    "Formation",
    "FormationError",
    "MotionBasis",
    "build_formation",
    "fit_rotation",
    "fit_shape",
    "motion_basis",
    "rigidity_matrix",
]
