"""The paper's force and worst-case analysis of a team: a safety certificate.

:func:`analyze` checks that the guidance can never ask more than the airframes
give (eq. T, Th and max of the paper) and finds the largest safe deformation;
``gcs analyze`` prints it, and a team that fails it is not flown.

Modules:

    ``_worst_case``  Force and worst-case analysis of a team (paper, section "Force and
                     worst case").
"""

from gcs.analysis._worst_case import Analysis, a_safe_span, analysis_json, analyze, format_report

__all__ = [
    "Analysis",
    "a_safe_span",
    "analysis_json",
    "analyze",
    "format_report",
]
