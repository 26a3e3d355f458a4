"""MkDocs hook of the documentation site: what the pages show of the code is generated from the code at build
time, never committed.

- ``<!-- generated: parameters KIND -->``: the parameters, initial values and outputs of the model ``KIND``
  (`rocking_model.models.MODELS`), each with its default, unit, allowed range and description, from the
  model's declarations (`parameters()`, ``INITIAL``, ``OUTPUTS``).
- ``<!-- generated: fmu-variables NAME -->``: the variables of the FMU ``NAME`` (the slave class's
  ``variables`` in `rocking_model.fmi.fmus`): causality, type, unit, start, range, description.
- ``<!-- generated: api-public -->``: an mkdocstrings entry per public name of `rocking_model` (its ``__all__``,
  resolved to the submodule that defines it).
- Math: the LaTeX of the pages (pymdownx.arithmatex, generic mode) becomes MathML (latex2mathml) in the built
  HTML, which browsers render natively: no script, nothing loaded from outside.
- The example gallery: the scripts of ``examples/`` are run into a temporary folder and their figures added to
  the site as ``gallery/<name>.png``. ``ROCKING_DOCS_GALLERY=skip`` leaves them out (the gallery page then says so);
  ``ROCKING_DOCS_GALLERY=<folder>`` reuses the figures of an earlier build kept there.
"""
from __future__ import annotations

import logging
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[2]
log = logging.getLogger("mkdocs.hooks.generate")

#: gallery figure -> (script, its arguments, what it shows). Each script runs in a fresh interpreter with
#: ``--out <scratch folder>`` and writes the figure there under the same name (never into the repository).
GALLERY = {
    "flexible_pulse.png": ("examples/flexible_pulse.py", [],
                           "The flexible rocking oscillator under a one-sine pulse, both schemes on top of each "
                           "other; the red lines are the impacts of the event-driven run."),
    "three_component.png": ("examples/three_component.py", [],
                            "The shipped three-component record: both components with the block's uplift "
                            "threshold, then each model's rotation with and without the vertical component."),
    "post_tensioned_pier.png": ("examples/post_tensioned_pier.py", [],
                                "A 1 m × 5 m, 20 t pier, free-standing and post-tensioned, under the shipped "
                                "record scaled to PGA 0.8 g and two one-sine pulses: rotation and tendon force."),
    "overturning_spectrum.png": ("examples/overturning_spectrum.py", ["--workers", "0"],
                                 "Overturning spectrum of the block b = 0.2 m, h = 1.0 m under one-sine pulses "
                                 "(667 event-driven cases, serial here): red squares overturned, blue circles did "
                                 "not (shade: max |φ|/α)."),
    "fragility.png": ("examples/fragility.py", ["--workers", "0"],
                      "Fragility curves of a slender block (b = 0.15 m, h = 1 m) for three damage states (|φ|max/α "
                      "≥ 0.2, ≥ 0.5, overturning) from a multiple-stripe analysis of 12 synthetic records × 16 "
                      "stripes of PGA/(g tan α): maximum-likelihood lognormal fits, 90 % bootstrap bands over "
                      "the records, and the observed fractions."),
}
#: tracked figures shown in the gallery as they are (they need FMUs and a second importer to redraw)
STATIC = {"system.png": ROOT / "examples" / "system" / "system.png"}


# --------------------------------------------------------------------------------------------------- tables
def _num(x) -> str:
    if isinstance(x, bool):
        return str(x).lower()
    if isinstance(x, float):
        if math.isinf(x):
            return "∞" if x > 0 else "−∞"
        return f"{x:g}"
    return str(x)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def parameter_table(kind: str) -> str:
    from rocking_model.models import MODELS

    cls = MODELS[kind]
    out = [f"**`{cls.__name__}`** (`kind = \"{kind}\"`)", "",
           "| name | role | default | unit | allowed range | description |", "| --- | --- | --- | --- | --- | --- |"]
    for role, params in (("parameter", cls.parameters()), ("initial value", cls.INITIAL), ("output", cls.OUTPUTS)):
        for p in params:
            default = "" if role == "output" else _num(p.default)
            rng = "" if role == "output" else p.range_text()
            out.append(f"| `{p.name}` | {role} | {_cell(default)} | {_cell(p.unit or '–')} | {_cell(rng)} | "
                       f"{_cell(p.description)} |")
    return "\n".join(out) + "\n"


def fmu_table(name: str) -> str:
    from rocking_model.fmi.fmus import FMUS
    from rocking_model.fmi.standalone import slave_instance

    cls = FMUS[name]
    # the value references pythonfmu gives the variables (their registration order), as in the modelDescription
    vrs = {var.name: vr for vr, var in slave_instance(cls).vars.items()}
    out = [f"**`{name}.fmu`**: {_cell(getattr(cls, 'description', '') or (cls.__doc__ or '').strip())}", "",
           "| name | value reference | causality | type | unit | start | range | description |",
           "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for v in cls.variables:
        start = "" if v.causality == "output" else _num(v.default)
        rng = v.range_text() if (v.min is not None or v.max is not None) else ""
        out.append(f"| `{v.name}` | {vrs[v.name]} | {v.causality} | {v.type} | {v.unit or '–'} | {_cell(start)} | "
                   f"{rng} | {_cell(v.description)} |")
    return "\n".join(out) + "\n"


def api_public() -> str:
    import rocking_model

    out = []
    for name in rocking_model.__all__:
        module = rocking_model._LAZY[name]
        # headed by the name a user imports (``from rocking_model import X``), documented where it is defined
        out.append(f"::: rocking_model.{module}.{name}\n    options:\n      show_root_full_path: false\n")
    return "\n".join(out)


_MARK = re.compile(r"<!-- generated: ([\w-]+)(?: (\w+))? -->")


def on_page_markdown(markdown, page, config, files, **kw):
    def repl(m):
        what, arg = m.group(1), m.group(2)
        if what == "parameters":
            return parameter_table(arg)
        if what == "fmu-variables":
            return fmu_table(arg)
        if what == "api-public":
            return api_public()
        if what == "gallery":
            return gallery_markdown()
        raise ValueError(f"{page.file.src_path}: unknown generated block {what!r}")
    return _MARK.sub(repl, markdown)


# --------------------------------------------------------------------------------------------------- gallery
_built: dict = {}
#: a 1 x 1 white PNG
_BLANK_PNG = bytes.fromhex("89504e470d0a1a0a0000000d4948445200000001000000010802000000907753de0000000c4944415478"
                           "9c63f8ffff3f0005fe02fea7d6a4e90000000049454e44ae426082")


def build_gallery(dest: Path) -> dict:
    """Run the gallery's scripts, each writing its figure into ``dest``: {figure: path or None}."""
    dest.mkdir(parents=True, exist_ok=True)
    done = {}
    env = dict(os.environ, MPLBACKEND="Agg")
    for fig, (script, argv, _) in GALLERY.items():
        out = dest / fig
        if not out.is_file():
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                r = subprocess.run([sys.executable, script, *argv, "--out", tmp], cwd=ROOT, env=env,
                                   capture_output=True, text=True, timeout=900)
                made = Path(tmp) / fig
                if r.returncode != 0 or not made.is_file():
                    raise RuntimeError(f"gallery: {script} failed:\n{r.stderr[-2000:]}")
                shutil.copyfile(made, out)
                log.info("gallery: %s in %.1f s", fig, time.perf_counter() - t0)
        done[fig] = out
    return done


def on_files(files, config, **kw):
    mode = os.environ.get("ROCKING_DOCS_GALLERY", "")
    _built.clear()
    if mode == "skip":          # a blank placeholder per figure, so that the pages that show one still link
        dest = Path(tempfile.mkdtemp(prefix="rocking-gallery-skipped-"))
        figures = {fig: dest / fig for fig in GALLERY}
        for path in figures.values():
            path.write_bytes(_BLANK_PNG)
        for fig, src in {**figures, **STATIC}.items():
            files.append(File.generated(config, f"gallery/{fig}", abs_src_path=str(src)))
        return files
    dest = Path(mode) if mode else Path(tempfile.mkdtemp(prefix="rocking-gallery-"))
    figures = build_gallery(dest)
    for fig, src in STATIC.items():
        figures[fig] = src
    _built.update(figures)
    for fig, src in figures.items():
        files.append(File.generated(config, f"gallery/{fig}", abs_src_path=str(src)))
    return files


def gallery_markdown() -> str:
    if not _built:
        return ("!!! note\n    This build skipped the gallery (`ROCKING_DOCS_GALLERY=skip`): its figures are drawn "
                "by `bash run.sh docs`.\n")
    out = []
    for fig, (script, argv, what) in GALLERY.items():
        shown = " ".join([script, *argv, "--out", "results"])
        out += [f"## {fig[:-4].replace('_', ' ').capitalize()}", "", f"![{fig[:-4]}](gallery/{fig})", "",
                f"{what} `python {shown}`", ""]
    out += ["## System co-simulation", "", "![system](gallery/system.png)", "",
            "Four FMUs in one system (`python examples/system/run.py`; needs the FMUs of `python build_fmu.py` and "
            "libcosimpy): see [co-simulation](guide/cosimulation.md). This figure is the tracked "
            "`examples/system/system.png`.", ""]
    return "\n".join(out)


# --------------------------------------------------------------------------------------------------- math
_MATH = re.compile(r'<(span|div) class="arithmatex">\s*\\([(\[])(.*?)\\[)\]]\s*</\1>', re.S)


def on_page_content(html, page, config, files, **kw):
    import html as html_lib

    from latex2mathml.converter import convert

    def repl(m):
        latex = html_lib.unescape(m.group(3))
        mathml = convert(latex, display="block" if m.group(2) == "[" else "inline")
        return mathml if m.group(1) == "span" else f'<div class="math">{mathml}</div>'
    return _MATH.sub(repl, html)
