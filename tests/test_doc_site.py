"""The documentation site: `mkdocs build --strict` (warnings are errors) builds it from mkdocs.yml; the tables it
generates are the code's declarations, its API reference has an entry per public name, its gallery is drawn
into the build (no tracked file written), and in a real browser (Debian's Chromium, driven by Playwright) every
page loads without a console error, a failed request, a broken internal link or a missing image. Screenshots of
the landing page and the API page are kept in results/docs_site/ (git-ignored).

Skips, naming the package, where MkDocs and its plugins (the `docs` extra) or the browser are missing."""
from __future__ import annotations

import functools
import http.server
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import threading
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS_PACKAGES = {"mkdocs": "mkdocs", "material": "mkdocs-material", "mkdocstrings": "mkdocstrings",
                 "mkdocstrings_handlers.python": "mkdocstrings-python", "latex2mathml": "latex2mathml"}
ARTEFACTS = ROOT / "results" / "docs_site"


def _missing(modules: dict) -> list[str]:
    out = []
    for mod, pkg in modules.items():
        try:
            found = importlib.util.find_spec(mod) is not None
        except ModuleNotFoundError:
            found = False
        if not found:
            out.append(pkg)
    return out


def _git_status() -> str:
    r = subprocess.run(["git", "status", "--porcelain", "--", "docs", "examples", "README.md"], cwd=ROOT,
                       capture_output=True, text=True, timeout=60)
    return r.stdout if r.returncode == 0 else ""


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    missing = _missing(DOCS_PACKAGES)
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (pip install -e '.[docs]')")
    out = tmp_path_factory.mktemp("site")
    before = _git_status()
    env = {k: v for k, v in os.environ.items() if k != "ROCKING_DOCS_GALLERY"}
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)], cwd=ROOT,
                       env=dict(env, MPLBACKEND="Agg", NO_MKDOCS_2_WARNING="1"), capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, "mkdocs build --strict failed:\n" + (r.stdout + r.stderr)[-5000:]
    assert _git_status() == before, "building the site changed files of the repository"
    return out


def test_site_builds_with_every_page(site):
    pages = {p.relative_to(site).as_posix() for p in site.rglob("*.html")}
    assert {"index.html", "api.html", "theory.html", "gallery.html", "architecture.html",
            "guide/models.html", "guide/fmus.html", "performance.html"} <= pages
    arch = (site / "architecture.html").read_text()
    assert "rk_engine.c" in arch, "the architecture page includes rocking_model/engine/DESIGN.md"
    theory = (site / "theory.html").read_text()
    assert theory.count("<math") > 20 and "arithmatex" not in theory, "the theory's equations became MathML"


def test_generated_tables_are_the_declarations(site):
    """The parameter tables (models page) and the FMU variable tables (FMU page) list every declared name with
    its range, as the code declares them today."""
    import html

    from rocking_model.fmi.fmus import FMUS
    from rocking_model.models import MODELS
    models = html.unescape((site / "guide" / "models.html").read_text())
    for kind, cls in MODELS.items():
        assert f"<code>{cls.__name__}</code>" in models, kind
        for p in (*cls.parameters(), *cls.INITIAL):
            assert re.search(rf"<td><code>{re.escape(p.name)}</code></td>", models), (kind, p.name)
            assert f"<td>{p.range_text()}</td>" in models, (kind, p.name, p.range_text())
        for p in cls.OUTPUTS:
            assert f"<td><code>{p.name}</code></td>" in models, (kind, p.name)
    fmus = html.unescape((site / "guide" / "fmus.html").read_text())
    for name, cls in FMUS.items():
        assert f"<code>{name}.fmu</code>" in fmus, name
        for v in cls.variables:
            assert f"<td><code>{v.name}</code></td>" in fmus, (name, v.name)


def test_fmu_page_quotes_the_value_references():
    """The non-Python host recipe of docs/guide/fmus.md names the value references of ag and phi that the FMU has."""
    from rocking_model.fmi.fmus import FMUS
    from rocking_model.fmi.standalone import slave_instance
    vrs = {var.name: vr for vr, var in slave_instance(FMUS["RigidRockingBlock"]).vars.items()}
    text = " ".join((ROOT / "docs" / "guide" / "fmus.md").read_text().split())
    assert f"value references {vrs['ag']} for `ag` and {vrs['phi']} for `phi`" in text
    assert f" {vrs['ag']} {vrs['phi']} 3.0 1.0 0.01" in text


def test_api_reference_has_every_public_name_and_module(site):
    import rocking_model
    api = (site / "api.html").read_text()
    for name in rocking_model.__all__:
        assert f'id="rocking_model.{rocking_model._LAZY[name]}.{name}"' in api, name
    for module in ("intensity", "fragility", "assessment", "ensemble", "records", "ground_motion", "models",
                   "fmi.build"):
        assert f'id="rocking_model.{module}"' in api, module
    assert 'id="rocking_model.intensity.intensity_measures"' in api


def test_gallery_is_drawn_into_the_build(site):
    from docs.hooks.generate import GALLERY, STATIC  # noqa: F401 (the hook's list of figures)
    for fig in [*GALLERY, *STATIC]:
        path = site / "gallery" / fig
        assert path.is_file() and path.stat().st_size > 10_000, fig
    assert 'src="gallery/flexible_pulse.png"' in (site / "gallery.html").read_text()


# ------------------------------------------------------------------------------------------------ browser
def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="module")
def server(site):
    handler = functools.partial(_QuietHandler, directory=str(site))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def test_every_page_in_a_browser(site, server):
    """Every page of the site in headless Chromium: no console error, no page error, no failed request, every
    image drawn, every internal link to a page or file of the site; the API page shows its entries."""
    chromium = _chromium()
    if chromium is None:
        pytest.skip("chromium not installed (Debian package chromium; bash run.sh test installs it as root)")
    if _missing({"playwright": "playwright"}):
        pytest.skip("playwright not installed (pip install -e '.[docs]')")
    from playwright.sync_api import sync_playwright

    pages = sorted(p.relative_to(site).as_posix() for p in site.rglob("*.html"))
    problems: list[str] = []
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, args=["--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            current = {"url": ""}
            page.on("console", lambda m: problems.append(f"{current['url']}: console {m.type}: {m.text}")
                    if m.type == "error" else None)
            page.on("pageerror", lambda e: problems.append(f"{current['url']}: page error: {e}"))
            # (a request the next navigation cancels, e.g. the favicon, fails with net::ERR_ABORTED: not a broken
            # resource; a missing file answers 404, caught below)
            page.on("requestfailed", lambda r: problems.append(f"{current['url']}: request failed: {r.url} "
                                                               f"({r.failure})")
                    if "ERR_ABORTED" not in (r.failure or "") else None)
            page.on("response", lambda r: problems.append(f"{current['url']}: HTTP {r.status}: {r.url}")
                    if r.status >= 400 else None)
            for rel in pages:
                if rel == "404.html":
                    continue
                current["url"] = rel
                page.goto(f"{server}/{rel}", wait_until="load")
                broken = page.eval_on_selector_all(
                    "img", "imgs => imgs.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src)")
                problems += [f"{rel}: image not drawn: {src}" for src in broken]
                for href in page.eval_on_selector_all("a[href]", "as => as.map(a => a.href)"):
                    url = urlparse(href)
                    if not href.startswith(server):
                        continue
                    target = site / unquote(url.path).lstrip("/")
                    if target.is_dir():
                        target = target / "index.html"
                    if not target.is_file():
                        problems.append(f"{rel}: broken link {href}")
                    elif url.fragment and target.suffix == ".html":
                        text = target.read_text()
                        if f'id="{unquote(url.fragment)}"' not in text:
                            problems.append(f"{rel}: broken anchor {href}")
                if rel == "index.html":
                    page.screenshot(path=str(ARTEFACTS / "index.png"))
                if rel == "api.html":
                    entries = page.locator(".doc-object").count()
                    if entries < 40:
                        problems.append(f"api.html: {entries} entries")
                    page.screenshot(path=str(ARTEFACTS / "api.png"))
        finally:
            browser.close()
    assert not problems, "\n".join(problems[:50])
    assert (ARTEFACTS / "index.png").stat().st_size > 10_000 and (ARTEFACTS / "api.png").stat().st_size > 10_000


def test_run_sh_docs_builds_the_site_strictly(run_sh_stubbed):
    """bash run.sh docs with a stand-in interpreter (each call only logged): it installs the docs extra, then runs
    `mkdocs build --strict` into site/, saying so first."""
    proc, calls = run_sh_stubbed("docs")
    assert proc.returncode == 0, proc.stderr
    assert any("install" in c and ".[docs" in c for c in calls), calls
    assert calls[-1] == "-m mkdocs build --strict --site-dir site", calls
    assert "building the documentation site into site/" in proc.stdout
