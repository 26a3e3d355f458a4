"""Every Python code block of the README and of docs/ runs, in order per page, and prints what the page quotes
(tests/doc_blocks.py)."""
from __future__ import annotations

import pytest

from doc_blocks import PAGES, ROOT, MissingOptional, needs_fmus, python_blocks, run_page, scratch_folder

PAGES_WITH_CODE = [p for p in PAGES if python_blocks(p.read_text())]


def test_pages_have_code_and_quoted_outputs():
    """The runner finds the blocks (so that the test below cannot pass by finding none): the README's two
    quickstarts quote their output."""
    readme = python_blocks((ROOT / "README.md").read_text())
    assert len(readme) == 2 and all(b.expected for b in readme)
    assert len(PAGES_WITH_CODE) >= 5


@pytest.mark.parametrize("page", PAGES_WITH_CODE, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_page_code_runs_and_prints_what_the_page_says(page, tmp_path, request):
    blocks = python_blocks(page.read_text())
    fmu_dir = None
    if needs_fmus(blocks):
        built = request.getfixturevalue("built_fmus")
        fmu_dir = next(iter(built.values())).parent
    cwd = scratch_folder(tmp_path, fmu_dir)
    try:
        printed, _ = run_page(page, blocks, cwd)
    except MissingOptional as exc:
        pytest.skip(str(exc))
    for b in blocks:
        if b.expected is not None:
            assert printed[b.line].strip() == b.expected.strip(), \
                f"{page.relative_to(ROOT)}:{b.line}: printed\n{printed[b.line]}\nthe page says\n{b.expected}"
