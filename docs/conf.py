"""Sphinx configuration of vemwear's documentation site.

Build with ``python -m sphinx -W -b html docs docs/_build/html`` (``pip install
".[docs]"``). The site is built offline: intersphinx links to NumPy, SciPy, meshio,
xarray and Dask are made only from inventories found on this machine (see
``_intersphinx``); without them those names render as plain code.
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS))  # docs/_ext
# the source tree first, so that a build from a clone documents that clone
sys.path.insert(0, str(ROOT / "src"))

from _ext.api_pages import write_api_pages  # noqa: E402
from _ext.config_reference import write_config_reference  # noqa: E402
from _ext.figure_scraper import ReturnedFigures  # noqa: E402

import vemwear  # noqa: E402

project = "vemwear"
author = "vemwear developers"
copyright = "vemwear developers, BSD 3-Clause"
release = version = vemwear.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_design",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_intersphinx", "gallery"]
templates_path = ["_templates"]
html_static_path = ["_static"]

# ----------------------------------------------------------------------------- Markdown
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 4  # the pages' [text](#heading) links
# README-style links out of docs/ (../src/..., ../examples/...) are links to the
# repository; they are rewritten by _ext.repo_links to the source on the web.
suppress_warnings = ["myst.header"]

# ----------------------------------------------------------------------------- API
autosummary_generate = True
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc sections hold the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks: set[str] = set()
# the types in Parameters/Returns become links where a target exists (not nitpicky:
# a type with no target stays text)
numpydoc_xref_param_type = True
numpydoc_xref_aliases = {
    # numpydoc's defaults for these are :ref:/:term: links into the Python and NumPy
    # glossaries, which warn without those inventories, or links written "python:str",
    # shown so when there is no inventory; plain object links do neither
    **{n: n for n in ("None", "True", "False", "list", "tuple", "str", "dict", "float")},
    **{"int": "int", "callable": "callable", "string": "str"},
    "bool": "bool",
    "boolean": "bool",
    "iterable": "collections.abc.Iterable",
    "sequence": "collections.abc.Sequence",
    "generator": "collections.abc.Generator",
    "array-like": "numpy.typing.ArrayLike",
    "array_like": "numpy.typing.ArrayLike",
    "scalar": "numpy.generic",
    "ndarray": "numpy.ndarray",
    "NDArray": "numpy.ndarray",
    "Dataset": "xarray.Dataset",
    "Client": "distributed.Client",
    "Mesh": "vemwear.mesh.Mesh",
    "Problem": "vemwear.simulate.Problem",
    "TimeGrid": "vemwear.simulate.TimeGrid",
    "Result": "vemwear.simulate.Result",
    "SolverOptions": "vemwear.simulate.SolverOptions",
    "Material": "vemwear.vem.Material",
    "ComplianceLaw": "vemwear.contact.ComplianceLaw",
    "Config": "vemwear.config.Config",
    "Study": "vemwear.studies.Study",
}
numpydoc_xref_ignore = {"of", "or", "optional", "default", "shape", "and", "with", "the", "a"}
add_module_names = False

# ----------------------------------------------------------------------------- gallery
sphinx_gallery_conf = {
    "examples_dirs": ["gallery"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_",
    "within_subsection_order": "_ext.gallery_order.ExampleOrder",
    "download_all_examples": False,
    "remove_config_comments": True,
    "reset_modules": ("matplotlib",),
    "matplotlib_animations": False,
    "show_memory": False,
    "thumbnail_size": (320, 224),
    "min_reported_time": 1,
    "abort_on_example_error": True,
    "plot_gallery": "True",
    # returned figures first: pyplot's scraper closes its figures, which then look alike
    "image_scrapers": (ReturnedFigures(), "matplotlib"),
}

# ----------------------------------------------------------------------------- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"vemwear {version}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "navbar_end": ["theme-switcher", "navbar-icon-links"],
}
html_sidebars = {"index": []}
html_show_sourcelink = False
html_last_updated_fmt = None


# ----------------------------------------------------------------------------- intersphinx
def _intersphinx() -> dict[str, tuple[str, str | None]]:
    """The intersphinx mappings whose inventories this machine has.

    Each project's inventory is looked for as ``NAME.inv`` in
    ``$VEMWEAR_INTERSPHINX_DIR`` (default ``docs/_intersphinx/``: ``objects.inv`` files
    saved from the projects' sites); with ``VEMWEAR_DOCS_ONLINE=1`` the others are
    fetched from the sites when the site is built. Without either the mapping is left
    out, so that an offline build is warning-free: references to that project render
    as code. (Debian's documentation packages were no substitute: their inventories of
    xarray and Dask hold no API objects.)
    """
    sites = {
        "python": "https://docs.python.org/3/",
        "numpy": "https://numpy.org/doc/stable/",
        "scipy": "https://docs.scipy.org/doc/scipy/",
        "meshio": "",  # meshio publishes no inventory: only a local file is used
        "xarray": "https://docs.xarray.dev/en/stable/",
        "dask": "https://docs.dask.org/en/stable/",
        "distributed": "https://distributed.dask.org/en/stable/",
    }
    local = Path(os.environ.get("VEMWEAR_INTERSPHINX_DIR", DOCS / "_intersphinx"))
    online = os.environ.get("VEMWEAR_DOCS_ONLINE") == "1"
    found: dict[str, tuple[str, str | None]] = {}
    for name, url in sites.items():
        inv = local / f"{name}.inv"
        if inv.is_file():
            found[name] = (url, str(inv))
        elif online and url:
            found[name] = (url, None)
    return found


intersphinx_mapping = _intersphinx()
intersphinx_timeout = 10

# matplotlib without a display; the gallery's figures only
os.environ.setdefault("MPLBACKEND", "Agg")
warnings.filterwarnings("ignore", message="Matplotlib is currently using agg")


def setup(app):  # type: ignore[no-untyped-def]
    write_config_reference(DOCS / "reference" / "config_keys.md")
    write_api_pages(DOCS / "reference" / "api")
    app.add_css_file("vemwear.css")
