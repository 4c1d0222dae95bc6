"""The documentation stays true: the README's test command is what CI runs, docs/fmu.md's
variable table matches the FMU, and every relative link points to an existing file and heading."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from conftest import REPO

from double_pendulum.component.variables import fmu_variables

README = (REPO / "README.md").read_text()
FMU_DOC = (REPO / "docs" / "fmu.md").read_text()
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")), REPO / "data" / "README.md"]

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


def _bash_blocks() -> list[str]:
    return re.findall(r"```bash\n(.*?)```", README, flags=re.S)


def test_readme_starts_with_the_two_commands_and_ci_runs_the_test_command():
    main_cmd, test_cmd = (block.strip() for block in _bash_blocks()[:2])
    assert "double-pendulum run all" in main_cmd
    assert "pytest" in test_cmd
    assert test_cmd in (REPO / ".ci" / "run").read_text()


def test_fmu_doc_variable_table_lists_every_variable_with_its_unit():
    for var in fmu_variables():
        row = next((line for line in FMU_DOC.splitlines() if line.startswith(f"| `{var.name}` |")), None)
        assert row is not None, f"{var.name} missing from the table in docs/fmu.md"
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[1] == var.causality and cells[2] == var.fmi_type
        assert cells[3] == (var.unit or "-")


def _anchors(page: Path) -> set[str]:
    """GitHub's heading anchors of a Markdown page (lower case, punctuation dropped, spaces to -)."""
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    headings = re.findall(r"^#{1,6}\s+(.+?)\s*$", text, flags=re.M)
    return {re.sub(r"[^\w\- ]", "", h.lower()).replace(" ", "-") for h in headings}


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_point_to_existing_files_and_headings(page: Path):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # absolute URL
        path, _, anchor = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        assert linked.is_file(), f"{page.relative_to(REPO)}: link to missing file {target}"
        assert linked.is_relative_to(REPO), f"{page.relative_to(REPO)}: link leaves the repository: {target}"
        if anchor and linked.suffix == ".md":
            assert anchor in _anchors(linked), f"{page.relative_to(REPO)}: no heading for {target}"


def test_docs_index_in_the_readme_lists_every_docs_page():
    for page in sorted((REPO / "docs").glob("*.md")):
        assert f"](docs/{page.name})" in README, f"README does not link docs/{page.name}"
