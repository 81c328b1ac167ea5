"""Write the README's tribometer figures from the gallery scripts that draw them.

``docs/figures/pin_wear_volume.png`` is the last figure of
``docs/gallery/plot_pin_on_disc.py`` and ``docs/figures/ball_scar_width.png`` that of
``docs/gallery/plot_ball_on_flat.py``, each run as sphinx-gallery runs it.

Usage::

    python docs/figures/make_tribometer_figures.py
"""

from __future__ import annotations

import runpy
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

HERE = Path(__file__).resolve().parent
GALLERY = HERE.parent / "gallery"
FIGURES = {
    "plot_pin_on_disc.py": "pin_wear_volume.png",
    "plot_ball_on_flat.py": "ball_scar_width.png",
}

for script, name in FIGURES.items():
    runpy.run_path(str(GALLERY / script), run_name="__main__")
    plt.figure(plt.get_fignums()[-1]).savefig(HERE / name, dpi=110)
    plt.close("all")
    print(f"wrote {HERE / name}")
