"""What users read is true: the README and docs/ name files that exist, cite nothing a user cannot follow
(no "issue N", "bug N" of the project's tracker), describe the simulator state the code has, and quote only
performance figures that a generated benchmark page contains; the command-line examples of the README and of
docs/ run. (The Python code blocks: tests/test_doc_blocks.py; the site's build: tests/test_doc_site.py.)"""
from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted([ROOT / "README.md"] + list((ROOT / "docs").rglob("*.md")))
#: written by another generator (tests/test_fault_suite.py writes its table), checked there
NOT_CHECKED_FOR_TRACKER_REFS: set = set()
#: folders whose files are outputs of a run (git-ignored), not files of the repository
GENERATED = ("dist/", "results/", "benchmarks/results/", ".venv/", "site/", "docs/gallery/")


def rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def tracked_files() -> set[str]:
    """The repository's files (tracked, and new ones not ignored), relative to its root."""
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"], cwd=ROOT,
                         capture_output=True, text=True, timeout=60)
    if out.returncode != 0:       # not a git checkout (an sdist): every file on disk is the repository
        return {rel(p) for p in ROOT.rglob("*") if p.is_file()}
    return set(out.stdout.splitlines())


TOP = sorted({p.name for p in ROOT.iterdir() if not p.name.startswith(".") or p.name == ".ci"} - {".venv", "site"})
#: a repository path in running text: starts with a top-level folder of the repository, optional ::name
_PATH = re.compile(r"(?<![\w./-])((?:%s)/[\w./*-]*)(?![\w./*<-])(?:::(\w+))?"
                   % "|".join(re.escape(t) for t in TOP if (ROOT / t).is_dir()))
_LINK = re.compile(r"\]\(([^)\s]+)\)")


def referenced_paths(doc: Path, text: str | None = None):
    """(path relative to the repository, test name or None, line number) of every repository path the page
    ``doc`` (its ``text``) names: markdown links (relative to the page) and paths in the text (relative to the
    repository root)."""
    text = doc.read_text() if text is None else text
    for n, line in enumerate(text.splitlines(), 1):
        for target in _LINK.findall(line):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            target = target.split("#")[0]
            path = (doc.parent / target).resolve().relative_to(ROOT).as_posix()
            if any(path.startswith(g) for g in GENERATED):      # the site's gallery, drawn at build time
                continue
            yield path, None, n
        for path, name in _PATH.findall(line):
            path = path.rstrip(".")                  # the end of a sentence
            if any(path.startswith(g) for g in GENERATED):
                continue
            yield path.rstrip("/"), name or None, n


def test_docs_name_only_files_of_the_repository():
    """Every path the README and docs/*.md name exists (a glob matches a file; a folder has files), and a
    ``file.py::test_name`` names a function of that file. `rocking_model/fmi.py`, named after it became the
    package rocking_model/fmi/, failed here."""
    files = tracked_files()
    folders = {p.as_posix() for f in files for p in Path(f).parents}
    bad = []
    for doc in DOCS:
        for path, name, n in referenced_paths(doc):
            if "*" in path:
                ok = any(Path(f).match(path) for f in files)
            else:
                ok = path in files or path in folders
            if ok and name:
                ok = re.search(rf"^\s*(?:async\s+)?def {re.escape(name)}\(", (ROOT / path).read_text(), re.M) \
                    is not None
            if not ok:
                bad.append(f"{rel(doc)}:{n}: {path}{'::' + name if name else ''}")
    assert not bad, "docs name files that the repository does not have:\n" + "\n".join(bad)


def test_referenced_path_pattern_finds_paths():
    """The check above sees the paths it must see (so that it cannot pass by finding nothing)."""
    line = ("see `rocking_model/fmi/` and [limitations](docs/limitations.md), tests/test_x.py::test_y, "
            "`tests/test_hard_*.py` and `dist/RigidRockingBlock.fmu`; `examples/<name>/` and benchmarks/run.py.")
    doc = ROOT / "README.md"
    found = {(p, name) for p, name, _ in referenced_paths(doc, line)}
    assert found == {("docs/limitations.md", None), ("rocking_model/fmi", None), ("tests/test_x.py", "test_y"),
                     ("tests/test_hard_*.py", None), ("benchmarks/run.py", None)}


_TRACKER = re.compile(r"\b(?:issues?|bugs?)\s+#?\d+", re.I)


def test_docs_cite_nothing_a_user_cannot_follow():
    """No page speaks of the project's tracker entries ("issue 15", "bug 7"), of notes outside the repository
    (physics.md) or of READMEs a user never saw ("the README's old quickstart"): a page cites files of the
    repository, papers, or states the scene's parameters."""
    bad = []
    for doc in DOCS:
        if rel(doc) in NOT_CHECKED_FOR_TRACKER_REFS:
            continue
        for n, line in enumerate(doc.read_text().splitlines(), 1):
            for pat in (_TRACKER, re.compile(r"physics(?:\.md| notes)"), re.compile(r"old quickstart", re.I)):
                for m in pat.finditer(line):
                    bad.append(f"{rel(doc)}:{n}: {m.group(0)!r}")
    assert not bad, "\n".join(bad)


# ------------------------------------------------------------------------------------------------ state table
def _table_after(text: str, heading: str) -> list[list[str]]:
    part = text.split(heading, 1)[1]
    rows, started = [], False
    for line in part.splitlines():
        if line.startswith("|"):
            started = True
            cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
            if not set("".join(cells)) <= set("-: "):
                rows.append(cells)
        elif started:
            break
    return rows


def test_robustness_library_state_table_is_the_state_of_the_code():
    """docs/robustness_library.md lists, per scheme, exactly the fields of `Simulator.get_state` (a "—" cell:
    not in that scheme's state), the state version of the code and the range of the mode codes."""
    from rocking_model import FlexibleOscillator, Mode, RigidBlock, Simulator
    from rocking_model.simulation import STATE_VERSION
    text = (ROOT / "docs" / "robustness_library.md").read_text()
    rows = _table_after(text, "### Plain-data state")
    header, rows = rows[0], rows[1:]
    assert header == ["Field", "Event-driven", "Moreau–Jean"]
    listed = {"event_driven": set(), "moreau_jean": set()}
    for field, ed, mj in rows:
        names = re.findall(r"`(\w+)`", field)
        assert names, field
        for scheme, cell in (("event_driven", ed), ("moreau_jean", mj)):
            if not cell.startswith("—"):
                listed[scheme].update(names)
        if "version" in names:
            assert re.search(rf"`version` \(int, {STATE_VERSION}\)", field), field
        if names == ["mode"]:
            assert f"0–{max(Mode)}" in ed and f"0–{max(Mode)}" in mj, (ed, mj)
    for model in (RigidBlock(), FlexibleOscillator()):
        for scheme in listed:
            sim = Simulator(model, scheme=scheme, phi_0=0.05)
            sim.advance(0.3, ag=0.0)
            assert set(sim.get_state()) == listed[scheme], (type(model).__name__, scheme)
    assert "to be merged" not in text.lower()


# ------------------------------------------------------------------------------------------------ figures
_BLOCK = re.compile(r"<!-- figures from ([^>]+?) -->(.*?)<!-- end of figures -->", re.S)
_NUM = r"\d+(?:\.\d+)?(?:e[-+−]?\d+)?"
_UNITS = ("ms", "µs", "s", "×", "%", "rad", "impacts", "cases/s", "steps")
_FIGURE = re.compile(rf"(?<![\w.−-])({_NUM})(?:\s?[–-]\s?({_NUM}))?\s?({'|'.join(map(re.escape, _UNITS))})(?![\w/])")


def _norm(number: str) -> str:
    m = re.fullmatch(r"(\d+(?:\.\d+)?)(?:e([-+−]?)0*(\d+))?", number)
    mant, sign, exp = m.groups()
    return mant if exp is None else f"{mant}e{'-' if sign in '-−' else ''}{exp}"


#: units that the pages' tables print in the column heading, not after each number
_UNIT_IN_HEADING = ("rad", "µs", "ratio", "cases/s")
_RATIO = re.compile(rf"\bratios? ({_NUM})(?:\s?[–-]\s?({_NUM}))?")


def figures(text: str):
    """(number, unit) of every figure in ``text``, a range a–b giving both ends; "ratio(s) a–b" gives
    dimensionless figures (unit "ratio")."""
    for a, b, unit in _FIGURE.findall(text):
        for x in (a, b) if b else (a,):
            yield _norm(x), unit
    for a, b in _RATIO.findall(text):
        for x in (a, b) if b else (a,):
            yield _norm(x), "ratio"


def page_has(page: str, number: str, unit: str) -> bool:
    """``number`` printed on the page as a figure of ``unit`` (rad, µs, ratios: anywhere, as the tables give
    their unit in the column heading)."""
    for m in re.finditer(rf"(?<![\w.])({_NUM})(?![\d.])", page):
        if _norm(m.group(1)) != number:
            continue
        after = page[m.end():m.end() + 12]
        if unit in _UNIT_IN_HEADING or re.match(rf"\s?{re.escape(unit)}(?![\w/])", after):
            return True
    return False


def test_docs_quote_only_figures_of_the_generated_pages():
    """Every figure (time, ratio, error, count) inside a block of the README or a docs/ page marked
    ``<!-- figures from PAGE ... -->`` ... ``<!-- end of figures -->`` is printed on one of the named pages,
    with its unit, as the benchmark scripts wrote them (rounding is not allowed: quote the page)."""
    blocks = [(doc, pages, body) for doc in DOCS for pages, body in _BLOCK.findall(doc.read_text())]
    assert len(blocks) >= 2, "the pages' performance paragraphs are marked"
    bad = []
    for doc, pages, body in blocks:
        text = "\n".join((ROOT / p).read_text() for p in pages.split())
        found = list(figures(body))
        assert found, body[:200]
        for number, unit in found:
            if not page_has(text, number, unit):
                bad.append(f"{rel(doc)}: {number} {unit} (from {pages})")
    assert not bad, "figures not on their pages:\n" + "\n".join(bad)


def test_figure_parser():
    body = ("in 4.53 ms on 7 s, 1.2–2.3× faster, 1e-8 rad and 3.1e-05 rad, 89 impacts, 2–4 % (tolerance 1e-8), "
            "time ratios 1.027–1.095")
    assert list(figures(body)) == [("4.53", "ms"), ("7", "s"), ("1.2", "×"), ("2.3", "×"), ("1e-8", "rad"),
                                   ("3.1e-5", "rad"), ("89", "impacts"), ("2", "%"), ("4", "%"),
                                   ("1.027", "ratio"), ("1.095", "ratio")]
    page = "| 1e-08 | ≤ 4.53 ms | 2.3× | T = 7 s | 3.1e-05 | 89 impacts | 1.2× | 2 % | 4 % | **1.027** | 1.095 |"
    assert all(page_has(page, n, u) for n, u in figures(body))
    assert not page_has(page, "3", "ms") and not page_has(page, "4.5", "ms") and not page_has(page, "7", "ms")


# ------------------------------------------------------------------------------------------------ CLI examples
def readme_cli_examples() -> list[str]:
    """The `rocking simulate` and `rocking ensemble` lines of the bash blocks of the README and docs/."""
    cmds = []
    for block in re.findall(r"```bash\n(.*?)```", "\n".join(d.read_text() for d in DOCS), re.S):
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("rocking simulate") or (line.startswith("rocking ensemble") and "..." not in line):
                if line not in cmds:
                    cmds.append(line)
    return cmds


def test_readme_cli_examples_name_files_the_repository_ships():
    """The records the README's `rocking` examples read are shipped (examples/records/), not files a user
    would have to find (RSN6_IMPVALL..., rec1.AT2)."""
    cmds = readme_cli_examples()
    assert any("--record" in c for c in cmds)
    for cmd in cmds:
        args = shlex.split(cmd)
        for i, a in enumerate(args):
            if a == "--record":
                for spec in args[i + 1:]:
                    if spec.startswith("--"):
                        break
                    if not spec.startswith("synthetic"):
                        assert (ROOT / spec).is_file(), f"{cmd}: {spec} is not in the repository"


@pytest.mark.parametrize("cmd", [c for c in readme_cli_examples() if c.startswith("rocking simulate")])
def test_readme_simulate_examples_run(cmd, tmp_path):
    """Each README `rocking simulate` example runs as written from the repository root, shortened to 1 s of
    motion and without the plot (bounded in time)."""
    args = shlex.split(cmd)[2:]
    if "--out" in args:                       # the example's output folder -> the test's
        args[args.index("--out") + 1] = str(tmp_path)
    else:
        args += ["--out", str(tmp_path)]
    args += ["--t-end", "1", "--no-plot", "--name", "run"]
    r = subprocess.run([sys.executable, "-m", "rocking_model.cli", "simulate", *args], cwd=ROOT,
                       capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr[-2000:]
    assert (tmp_path / "run.csv").is_file()
    assert "impacts" in r.stdout


# ------------------------------------------------------------------------------------------------ shipped record
def test_shipped_record_is_the_synthetic_record_it_says():
    """examples/records/synthetic_2017.AT2 is what examples/records/make_synthetic_record.py writes:
    `synthetic_record(seed=2017)` in g with PEER's 7 digits, its header saying it is synthetic."""
    import numpy as np

    from rocking_model.records import read_at2, synthetic_record
    path = ROOT / "examples" / "records" / "synthetic_2017.AT2"
    rec = read_at2(path)
    t, ag = synthetic_record(seed=2017)
    assert np.array_equal(rec.t, t)
    # 7 significant digits in g; other CPUs' round-off changes the record by far less than that
    assert np.allclose(rec.ag, ag, rtol=0, atol=1e-6 * np.max(np.abs(ag)))
    assert "synthetic" in " ".join(rec.header).lower()


def test_shipped_csv_record_is_the_at2_record():
    """examples/records/synthetic_2017.csv (the docs' CSV example) is the shipped AT2 record read back and written
    in cm/s2, as examples/records/make_synthetic_record.py writes it; its header states the units."""
    import numpy as np

    from rocking_model.records import read_at2, read_csv
    folder = ROOT / "examples" / "records"
    at2, csv = read_at2(folder / "synthetic_2017.AT2"), read_csv(folder / "synthetic_2017.csv")
    assert (folder / "synthetic_2017.csv").read_text().splitlines()[0] == "time [s],ag [cm/s2]"
    assert np.array_equal(at2.t, csv.t) and np.allclose(at2.ag, csv.ag, rtol=1e-12, atol=0)


# ------------------------------------------------------------------------------------------------ benchmark pages
def test_benchmark_cold_start_runs_for_a_source_fmu(built_fmus):
    """The cold-start benchmark steps every FMU, a source without inputs included: it used to set the output
    ag of GroundMotionSource (fmi2SetReal: fmi2Error) and printed the traceback into docs/performance.md.
    Nothing here asserts a time."""
    from benchmarks import fmu_bench
    for name in ("GroundMotionSource", "RigidRockingBlock"):
        r = fmu_bench.cold_start(built_fmus[name], repeats=1)
        assert "error" not in r, r.get("error", "")[-1000:]
        assert set(r) >= {"import_fmpy", "read_and_extract", "instantiate_to_first_step"}


def test_generated_pages_name_no_directory_of_the_machine():
    """The report writer replaces the machine's directories by placeholders, a failure becomes one line, and the
    committed pages hold no traceback and no absolute path of a user's or build machine's folders."""
    import tempfile

    from benchmarks import report
    # (a scratch name no checkout has: the repository itself may be cloned into the temp folder)
    scratch = "rocking-scrub-test-f3c1"
    text = f"{report.REPO_ROOT}/docs and {sys.prefix}/lib and {tempfile.gettempdir()}/{scratch}"
    scrubbed = report.scrub_paths(text)
    assert scrubbed == f"<repo>/docs and <python>/lib and <tmp>/{scratch}"
    tb = (f'Traceback (most recent call last):\n  File "{sys.prefix}/lib/fmpy/fmi2.py", line 441, in setReal\n'
          "fmpy.fmi2.FMICallException: fmi2SetReal failed with status 3 (error)")
    line = report.failure_line(tb)
    assert line == "fmpy.fmi2.FMICallException: fmi2SetReal failed with status 3 (error)"
    machine_dir = re.compile(r"(?<![\w.<])/(?:work|home|root|tmp|Users|opt|mnt|srv)/")
    for page in [ROOT / "docs" / "performance.md", *sorted((ROOT / "docs" / "performance").glob("*.md"))]:
        body = page.read_text()
        assert "Traceback" not in body and "failed:" not in body, rel(page)
        assert not machine_dir.search(body), (rel(page), machine_dir.search(body).group(0))


def test_readme_is_short_and_says_what_a_newcomer_needs():
    """The README stays a page a newcomer reads (at most 200 lines; the rest is in docs/): what the project is with
    its paper, the two set-up commands, activating .venv, both quickstarts, which FMU to pick, where the docs are,
    how to cite."""
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    for needed in ("doi:10.1007/s10518-016-0068-4", "bash run.sh demo", "bash run.sh test", "source .venv/bin/activate",
                   "## Quickstart: Python", "## Quickstart: FMU with fmpy", "## Which FMU to pick",
                   "bash run.sh docs", "## How to cite"):
        assert needed in readme, needed
