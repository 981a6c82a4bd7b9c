"""The documentation stands on its own: every relative link resolves to a file in the
repository, and every ```python block of README.md and docs/ runs (issue 16).

Blocks of one file run in order in one namespace, in a scratch folder that sees the
repository's ``netlists/`` and ``examples/``.  A block preceded by
``<!-- docs-test: study REASON -->`` (a minute or more) runs only with ``-m study``
(CI runs those); ``<!-- docs-test: skip REASON -->`` never runs, and needs a reason.
"""
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
         *sorted((ROOT / "examples").rglob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(\s*([^)\s]+)[^)]*\)|<img[^>]+src=\"([^\"]+)\"")
BLOCK = re.compile(r"(?:<!-- docs-test: (\w+)\s*([^>]*?)\s*-->\s*\n)?```python\n(.*?)```",
                   re.S)


def relative_links(page: Path):
    for match in LINK.finditer(page.read_text()):
        target = (match.group(1) or match.group(2)).split("#")[0]
        if target and not re.match(r"[a-z]+:", target):
            yield target


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_names_a_file_of_the_repository(page):
    missing = [t for t in relative_links(page) if not (page.parent / t).resolve().exists()]
    outside = [t for t in relative_links(page)
               if not (page.parent / t).resolve().is_relative_to(ROOT)]
    assert not missing and not outside, (missing, outside)


def blocks(page: Path, study: bool):
    """(line, code) of the blocks to run."""
    text = page.read_text()
    for match in BLOCK.finditer(text):
        mark, reason, code = match.groups()
        line = text[:match.start(3)].count("\n") + 1
        assert mark in (None, "skip", "study"), f"{page.name}:{line}: unknown mark {mark}"
        assert mark is None or reason, f"{page.name}:{line}: a {mark} mark needs a reason"
        if mark is None or (mark == "study" and study):
            yield line, code


def run_page(page, tmp_path, study):
    import matplotlib

    from pneunet.physics.valve_effects import available_effects, unregister_effect
    from pneunet.truth.circuits.effects import registered_effects, unregister

    matplotlib.use("Agg")
    for name in ("netlists", "examples"):
        (tmp_path / name).symlink_to(ROOT / name)
    namespace = {"__name__": "__docs__"}
    cwd = os.getcwd()
    valve_effects, circuit_effects = set(available_effects()), set(registered_effects())
    os.chdir(tmp_path)
    try:
        for line, code in blocks(page, study):
            try:
                exec(compile(code, f"{page.name}:{line}", "exec"), namespace)
            except Exception as exc:
                raise AssertionError(f"{page.relative_to(ROOT)}, block at line {line}: "
                                     f"{type(exc).__name__}: {exc}") from exc
    finally:
        os.chdir(cwd)
        for effect in set(available_effects()) - valve_effects:  # a page's own effects
            unregister_effect(effect)
        for effect in set(registered_effects()) - circuit_effects:
            unregister(effect.name)


WITH_CODE = [p for p in PAGES if "```python" in p.read_text()]
WITH_STUDY = [p for p in WITH_CODE if "<!-- docs-test: study" in p.read_text()]


@pytest.mark.parametrize("page", WITH_CODE, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_python_block_runs(page, tmp_path):
    run_page(page, tmp_path, study=False)


@pytest.mark.study
@pytest.mark.parametrize("page", WITH_STUDY, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_python_block_runs_including_the_long_ones(page, tmp_path):
    run_page(page, tmp_path, study=True)


def test_the_gallery_shows_every_figure_make_all_draws_and_names_every_plot_function():
    gallery = (ROOT / "docs" / "gallery.md").read_text()
    shown = {t for t in relative_links(ROOT / "docs" / "gallery.md") if t.endswith(".png")}
    drawn = {str(p.relative_to(ROOT / "docs")) for p in
             (ROOT / "docs" / "figures" / "gallery").rglob("*.png")}
    assert shown == drawn
    script = (ROOT / "docs" / "figures" / "make_all.py").read_text()
    plotters = {m for path in (ROOT / "pneunet").rglob("*.py")
                for m in re.findall(r"^def (plot_\w+)", path.read_text(), re.M)}
    assert plotters and not [f for f in plotters if f not in script and f not in gallery]
