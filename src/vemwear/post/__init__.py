"""Post-processing: saving and loading runs, figures, and ParaView output.

- :mod:`~vemwear.post.results`: ``result.npz`` (every array documented there) and
  ``summary.json``; :func:`save_result`, :func:`load_result`.
- :mod:`~vemwear.post.plots`: the paper's figures (contact profiles, displacement maps,
  comparisons) plus the deformed mesh and time histories, as matplotlib figures.
- :mod:`~vemwear.post.vtk`: a ``.pvd`` time series of ``.vtu`` files for ParaView.
- :mod:`~vemwear.post.norms`: norms of projected displacements and of the wear, errors
  against exact solutions.
- :mod:`~vemwear.post.compare`: errors against a reference solution on a nested mesh
  (Example 5.5), convergence orders; :mod:`~vemwear.post.prolong`: coarse functions at
  fine points.

Names are imported on first use (matplotlib only with the figures), so that importing
the package stays cheap.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..util.lazy import lazy_names

if TYPE_CHECKING:
    from .compare import (
        Comparison,
        ErrorHistory,
        Solution,
        common_levels,
        convergence_orders,
        solution_errors,
    )
    from .maps import plot_deformed, plot_displacement
    from .norms import (
        ProjectedNorms,
        contact_l2_norm,
        displacement_error,
        exact_errors,
        projected_norm,
        wear_error,
    )
    from .plots import QUANTITIES, compare_profiles, plot_contact_profiles, plot_time_history
    from .results import (
        load_result,
        load_summary,
        mesh_from_arrays,
        result_arrays,
        save_result,
        summarize,
    )
    from .vtk import cell_strain_stress, write_vtk_series

_WHERE = {
    "Comparison": "compare",
    "ErrorHistory": "compare",
    "Solution": "compare",
    "common_levels": "compare",
    "convergence_orders": "compare",
    "solution_errors": "compare",
    "plot_deformed": "maps",
    "plot_displacement": "maps",
    "ProjectedNorms": "norms",
    "contact_l2_norm": "norms",
    "displacement_error": "norms",
    "exact_errors": "norms",
    "projected_norm": "norms",
    "wear_error": "norms",
    "QUANTITIES": "plots",
    "compare_profiles": "plots",
    "plot_contact_profiles": "plots",
    "plot_time_history": "plots",
    "load_result": "results",
    "load_summary": "results",
    "mesh_from_arrays": "results",
    "result_arrays": "results",
    "save_result": "results",
    "summarize": "results",
    "cell_strain_stress": "vtk",
    "write_vtk_series": "vtk",
}
__all__ = [
    "QUANTITIES",
    "Comparison",
    "ErrorHistory",
    "ProjectedNorms",
    "Solution",
    "cell_strain_stress",
    "common_levels",
    "compare_profiles",
    "contact_l2_norm",
    "convergence_orders",
    "displacement_error",
    "exact_errors",
    "load_result",
    "load_summary",
    "mesh_from_arrays",
    "plot_contact_profiles",
    "plot_deformed",
    "plot_displacement",
    "plot_time_history",
    "projected_norm",
    "result_arrays",
    "save_result",
    "solution_errors",
    "summarize",
    "wear_error",
    "write_vtk_series",
]


__getattr__, __dir__ = lazy_names(__name__, {k: f".{v}" for k, v in _WHERE.items()})
