"""Today's figures, in one place: tests/figures.yaml holds what each accuracy test last
measured, the margin its ceiling leaves, and where the docs print it.

A test calls ``hold(key, value)``: the value must be at most ``measured + margin``. Set
``VSMATCH_RECORD_FIGURES=FILE`` to have every held value written to FILE as well (one
``key: value`` line each), then ``python tests/figures.py FILE`` prints which figures moved
and, with ``--write``, puts the new ones into tests/figures.yaml (the docs' tables are
re-made by the commands they name; tests/test_figures.py fails until they agree).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import yaml

FILE = Path(__file__).with_name("figures.yaml")
FIGURES: dict = yaml.safe_load(FILE.read_text())


def ceiling(key: str) -> float:
    figure = FIGURES[key]
    return figure["measured"] + figure["margin"]


def hold(key: str, value: float) -> None:
    """Assert ``value`` is within the ceiling of figure ``key`` (and record it when asked)."""
    record = os.environ.get("VSMATCH_RECORD_FIGURES")
    if record:
        with open(record, "a") as out:
            out.write(f"{key}: {float(value):.6g}\n")
    figure = FIGURES[key]
    assert value <= ceiling(key), (
        f"{key}: {value:.4g} above its ceiling {ceiling(key):.4g} "
        f"(measured {figure['measured']} + margin {figure['margin']})")


def documented(figure: dict, repo: Path) -> tuple[float, int] | None:
    """The number the docs print for a figure (its ``doc``: file, a table row's first cell,
    the column after it, and which number of the cell), with its decimal places."""
    if "doc" not in figure:
        return None
    name, row, column, *part = figure["doc"]
    for line in (repo / name).read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0].replace("**", "") == row:
            numbers = re.findall(r"\d+\.\d+|\d+", cells[column])
            text = numbers[part[0] if part else 0]
            return float(text), len(text.split(".")[1]) if "." in text else 0
    raise LookupError(f"{name} has no table row {row!r}")


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__)
        return 2
    seen: dict[str, list[float]] = {}
    for line in Path(argv[0]).read_text().splitlines():
        key, value = line.rsplit(": ", 1)
        seen.setdefault(key, []).append(float(value))
    text = FILE.read_text()
    for key, values in sorted(seen.items()):
        old = FIGURES[key]["measured"]
        new = max(values)
        mark = "" if abs(new - old) < 5e-3 * max(abs(old), 1e-3) else "   <- moved"
        print(f"{key:45s} {old:>10.4g} {new:>10.4g}{mark}")
        if mark and "--write" in argv:
            decimals = len(str(old).split(".")[1]) if "." in str(old) else 0
            pattern = rf"(\n{re.escape(key)}:\n  measured: )[^\n]+"
            text = re.sub(pattern, rf"\g<1>{new:.{max(decimals, 2)}f}", text)
    if "--write" in argv:
        FILE.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
