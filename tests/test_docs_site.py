"""The built documentation site renders in a real browser and has no broken internal link.

The site is built by ``python -m sphinx -W -b html docs docs/_build/html`` (README,
"Documentation"; ``.ci/run`` builds it before the tests). Headless Chromium (Debian's
``chromium``) opens the home page, the gallery and one gallery page: each gives a
screenshot that is not blank, the theme's scripts have run, and the gallery shows a
thumbnail for every example. A crawler over the built HTML checks every internal link
and anchor. In CI (``CI=true``) a missing site or browser is a failure; elsewhere the
tests are skipped, saying why.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
SITE = ROOT / "docs" / "_build" / "html"
GALLERY = ROOT / "docs" / "gallery"
SHOTS = ROOT / "docs" / "_build" / "screenshots"
IN_CI = os.environ.get("CI", "").lower() == "true"
BUILD = "python -m sphinx -W -b html docs docs/_build/html"

#: Chromium's flags: no sandbox (root in CI), no GPU, no network of its own, a fresh
#: profile per run.
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


def _missing(what: str) -> None:
    """Fail in CI, skip elsewhere: the check must not pass silently where it cannot run."""
    if IN_CI:
        pytest.fail(f"{what} (CI=true: .ci/run builds the site and installs chromium)")
    pytest.skip(what)


@pytest.fixture(scope="module")
def site() -> Path:
    if not (SITE / "index.html").is_file():
        _missing(f"no built site at {SITE}: build it with `{BUILD}`")
    return SITE


@pytest.fixture(scope="module")
def chromium() -> str:
    for name in ("/usr/bin/chromium", "chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    _missing("no chromium: apt-get install -y chromium")
    raise AssertionError  # unreachable


def _browse(chromium: str, page: Path, profile: Path, *args: str) -> subprocess.CompletedProcess:
    cmd = [chromium, *FLAGS, f"--user-data-dir={profile}", *args, page.as_uri()]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False)


def _screenshot(chromium: str, page: Path, out: Path, profile: Path) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    out.unlink(missing_ok=True)
    run = _browse(chromium, page, profile, "--window-size=1280,1400", f"--screenshot={out}")
    assert out.is_file(), f"no screenshot of {page}: {run.stderr[-2000:]}"


def _check_not_blank(path: Path) -> None:
    from PIL import Image

    with Image.open(path) as im:
        assert im.format == "PNG" and im.size == (1280, 1400)
        rgb = im.convert("RGB")
        colours = rgb.getcolors(maxcolors=1 << 20) or []
        # a rendered page has text, a navigation bar and figures: many colours, and
        # content in its top, middle and lower thirds
        assert len(colours) > 200, f"{path.name}: {len(colours)} colours"
        for top in (0, 466, 933):
            band = rgb.crop((0, top, 1280, top + 466)).getcolors(maxcolors=1 << 20) or []
            assert len(band) > 20, f"{path.name}: rows {top}-{top + 466} look empty"


def test_home_page_renders(site: Path, chromium: str, tmp_path: Path) -> None:
    _screenshot(chromium, site / "index.html", SHOTS / "index.png", tmp_path / "p1")
    _check_not_blank(SHOTS / "index.png")
    dom = _browse(chromium, site / "index.html", tmp_path / "p2", "--dump-dom").stdout
    # the theme's scripts ran (they set the colour mode on <html>) and the page is ours
    assert re.search(r"<html[^>]*data-theme=\"(light|dark)\"", dom), dom[:500]
    for text in ("vemwear", "Tutorials", "Gallery", "API reference"):
        assert text in dom


def test_gallery_shows_every_example(site: Path, chromium: str, tmp_path: Path) -> None:
    index = site / "auto_examples" / "index.html"
    assert index.is_file()
    _screenshot(chromium, index, SHOTS / "gallery.png", tmp_path / "p1")
    _check_not_blank(SHOTS / "gallery.png")
    dom = _browse(chromium, index, tmp_path / "p2", "--dump-dom").stdout
    thumbs = re.findall(r"<img[^>]*src=\"([^\"]*sphx_glr_(plot_\w+?)_thumb\.png)\"", dom)
    names = {f"{name}.py" for _, name in thumbs}
    assert names == {p.name for p in GALLERY.glob("plot_*.py")}
    from PIL import Image

    for src, _ in thumbs:  # each thumbnail is a real image of the example's figure
        with Image.open(index.parent / src) as im:
            assert im.size[0] >= 100 and len(im.convert("RGB").getcolors(1 << 20) or []) > 50


def test_a_gallery_page_renders_its_figures(site: Path, chromium: str, tmp_path: Path) -> None:
    page = site / "auto_examples" / "plot_example_5_2.html"
    _screenshot(chromium, page, SHOTS / "example_5_2.png", tmp_path / "p1")
    _check_not_blank(SHOTS / "example_5_2.png")
    dom = _browse(chromium, page, tmp_path / "p2", "--dump-dom").stdout
    figures = re.findall(r"src=\"(\.\./_images/sphx_glr_plot_example_5_2_\d+\.png)\"", dom)
    assert len(set(figures)) == 2 and all((page.parent / f).is_file() for f in figures)
    assert "Pinned" in dom and "max_wear" in dom  # its text and its code


# ----------------------------------------------------------------------------- links
class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key) and (key == "id" or tag == "a"):
                self.ids.add(str(a[key]))
        for key in ("href", "src"):
            if a.get(key) and not (tag == "link" and a.get("rel") in ("preload", "dns-prefetch")):
                self.links.append(str(a[key]))


def _parse(path: Path) -> _Links:
    p = _Links()
    p.feed(path.read_text(encoding="utf-8", errors="replace"))
    return p


def broken_links(site: Path) -> tuple[int, list[str]]:
    """The internal links of the site's pages (``href`` and ``src``, with their anchors)
    that lead nowhere, and how many were checked; the theme's own template copies under
    ``_static/`` are no pages."""
    pages = sorted(p for p in site.rglob("*.html") if "_static" not in p.relative_to(site).parts)
    parsed = {p: _parse(p) for p in pages}
    broken = []
    checked = 0
    for page, links in parsed.items():
        for link in links.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or link.startswith(("mailto:", "javascript:")):
                continue  # external: not ours to check offline
            path, frag = urldefrag(link)
            target = (page.parent / unquote(urlsplit(path).path)).resolve() if path else page
            if target.is_dir():
                target = target / "index.html"
            checked += 1
            if not target.is_file():
                broken.append(f"{page.relative_to(site)}: {link} (no such file)")
            elif frag and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else _parse(target).ids
                if unquote(frag) not in ids:
                    broken.append(f"{page.relative_to(site)}: {link} (no anchor)")
    return checked, broken


def test_the_crawler_finds_broken_links(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text(
        '<a href="sub/page.html#here">ok</a> <a href="sub/page.html#gone">no anchor</a>'
        '<img src="missing.png"> <a href="https://example.org/x">external</a>'
        '<a href="#top" id="top">self</a>'
    )
    (tmp_path / "sub" / "page.html").write_text('<h1 id="here">x</h1><a href="../index.html">')
    checked, broken = broken_links(tmp_path)
    assert checked == 5
    assert broken == [
        "index.html: sub/page.html#gone (no anchor)",
        "index.html: missing.png (no such file)",
    ]


def test_no_internal_link_is_broken(site: Path) -> None:
    checked, broken = broken_links(site)
    assert checked > 1000, checked
    assert not broken, f"{len(broken)} broken links:\n" + "\n".join(broken[:40])


def test_every_public_name_has_its_page(site: Path) -> None:
    """Every name of the public packages' ``__all__`` is rendered: on its own page, or
    (a name two packages export) on the page of the package that documents it."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("api_pages", ROOT / "docs/_ext/api_pages.py")
    assert spec is not None and spec.loader is not None
    api = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(api)
    names = api.public_names()
    assert {p for p, _ in api.PACKAGES} >= {
        f"vemwear.{p}"
        for p in ("mesh", "vem", "contact", "solvers", "simulate", "post", "runner", "studies")
    }
    missing = []
    for pkg, rows in names.items():
        text = (site / "reference" / "api" / f"{pkg}.html").read_text(encoding="utf-8")
        for name, path in rows:
            page = site / "reference" / "api" / "generated" / f"{path}.html"
            if not page.is_file() or f"generated/{path}.html" not in text:
                missing.append(f"{pkg}.{name}")
            elif 'id="' + path + '"' not in page.read_text(encoding="utf-8"):
                missing.append(f"{pkg}.{name} (no description of {path})")
    assert not missing, missing
    assert sum(len(r) for r in names.values()) > 140
