"""The Python code blocks of the README and of docs/: extracted, run in order per page in a scratch folder that has
the repository's example records (and the session's FMUs as dist/), and their printed output compared with the
output the page quotes.

A page quotes a block's output in a ```text block that follows it, with at most one line of prose between them
("prints"). Blocks run in one namespace per page, in a fresh interpreter, from the scratch folder."""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md"] + list((ROOT / "docs").rglob("*.md")))
_FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.S | re.M)
MARK = "@@rocking-doc-block@@"
#: modules of optional extras: a page whose code needs one that is missing is skipped, naming it
OPTIONAL = {"libcosimpy": "cosim", "ecospy": "ecos", "dask": "ensemble", "distributed": "ensemble",
            "pyarrow": "parquet", "matplotlib": "plot"}


class MissingOptional(Exception):
    """A page's code needs a module of an optional extra that is not installed."""


@dataclass
class Block:
    line: int                   # line of the opening fence
    code: str
    expected: str | None        # the quoted output, or None


def python_blocks(text: str) -> list[Block]:
    fences = [(m.group(1), m.group(2), m.start(), m.end()) for m in _FENCE.finditer(text)]
    out = []
    for i, (lang, body, start, end) in enumerate(fences):
        if lang != "python":
            continue
        expected = None
        if i + 1 < len(fences) and fences[i + 1][0] == "text":
            between = text[end:fences[i + 1][2]].strip()
            if len(between.splitlines()) <= 1 and "```" not in between:
                expected = fences[i + 1][1]
        out.append(Block(text.count("\n", 0, start) + 1, body, expected))
    return out


def needs_fmus(blocks: list[Block]) -> bool:
    return any("dist/" in b.code or "examples/system" in b.code for b in blocks)


def scratch_folder(tmp: Path, fmu_dir: Path | None) -> Path:
    """tmp with examples/ (records linked, the system example copied, so that its ../../dist is tmp/dist) and
    dist/ (the FMUs)."""
    ex = tmp / "examples"
    ex.mkdir()
    for child in (ROOT / "examples").iterdir():
        if child.name == "system":
            shutil.copytree(child, ex / "system")
        else:
            (ex / child.name).symlink_to(child)
    if fmu_dir is not None:
        (tmp / "dist").symlink_to(fmu_dir)
    return tmp


_DRIVER = """
import json, sys
page, blocks = sys.argv[1], json.loads(sys.stdin.read())
ns = {"__name__": "__main__"}
for line, code in blocks:
    print(%r, line, flush=True)
    exec(compile(code, f"{page}:{line}", "exec"), ns)
    sys.stdout.flush()
""" % MARK


def run_page(page: Path, blocks: list[Block], cwd: Path, timeout: float = 600) -> tuple[dict, str]:
    """Run the page's blocks in order in one interpreter in ``cwd``: ({line: printed output}, stderr)."""
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT))
    r = subprocess.run([sys.executable, "-c", _DRIVER, page.relative_to(ROOT).as_posix()],
                       input=json.dumps([(b.line, b.code) for b in blocks]), cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        m = re.search(r"ModuleNotFoundError: No module named '([\w.]+)'", r.stderr)
        if m and m.group(1).split(".")[0] in OPTIONAL:
            top = m.group(1).split(".")[0]
            raise MissingOptional(f"{top} not installed (the '{OPTIONAL[top]}' extra)")
        raise AssertionError(f"{page.relative_to(ROOT)}: a code block failed:\n{r.stderr[-3000:]}")
    printed, line = {}, None
    for row in r.stdout.splitlines(keepends=True):
        if row.startswith(MARK):
            line = int(row.split()[1])
            printed[line] = ""
        elif line is not None:
            printed[line] += row
    return printed, r.stderr
