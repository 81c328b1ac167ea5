"""The order of the gallery: the paper's examples first, then beyond the paper, then
studies (a name missing here sorts last, alphabetically)."""

from __future__ import annotations

ORDER = (
    "plot_example_5_2.py",
    "plot_example_5_3.py",
    "plot_example_5_4.py",
    "plot_example_5_5.py",
    "plot_orders_k2.py",
    "plot_punch.py",
    "plot_block_displacement.py",
    "plot_fretting.py",
    "plot_3d.py",
    "plot_pin_on_disc.py",
    "plot_hertz.py",
    "plot_ball_on_flat.py",
    "plot_adaptive_moving.py",
    "plot_sweep.py",
    "plot_fit.py",
)


class ExampleOrder:
    """sphinx-gallery's ``within_subsection_order``: a sort key of the file names."""

    def __init__(self, src_dir: str) -> None:
        self.src_dir = src_dir

    def __call__(self, filename: str) -> tuple[int, str]:
        return (ORDER.index(filename) if filename in ORDER else len(ORDER), filename)

    def __repr__(self) -> str:  # sphinx-gallery caches the configuration by its repr
        return f"{type(self).__name__}()"
