"""Post-processing: saving and loading runs, figures, and ParaView output.

- :mod:`~vemwear.post.results`: ``result.npz`` (every array documented there) and
  ``summary.json``; :func:`save_result`, :func:`load_result`.
- :mod:`~vemwear.post.plots`: the paper's figures (contact profiles, displacement maps,
  comparisons) plus the deformed mesh and time histories, as matplotlib figures.
- :mod:`~vemwear.post.vtk`: a ``.pvd`` time series of ``.vtu`` files for ParaView.
"""

from .plots import (
    QUANTITIES,
    compare_profiles,
    plot_contact_profiles,
    plot_deformed,
    plot_displacement,
    plot_time_history,
)
from .results import (
    load_result,
    load_summary,
    mesh_from_arrays,
    result_arrays,
    save_result,
    summarize,
)
from .vtk import cell_strain_stress, write_vtk_series

__all__ = [
    "QUANTITIES",
    "cell_strain_stress",
    "compare_profiles",
    "load_result",
    "load_summary",
    "mesh_from_arrays",
    "plot_contact_profiles",
    "plot_deformed",
    "plot_displacement",
    "plot_time_history",
    "result_arrays",
    "save_result",
    "summarize",
    "write_vtk_series",
]
