"""Deliberate faults, one at a time, in a copy of the tree: the tests that guard each must
fail. A test suite that still passes with a stage turned off, a refusal removed or a figure
made worse cannot catch that regression.

    python scripts/mutations.py              # every mutation, a markdown table at the end
    python scripts/mutations.py --only scanline-off --only exposure-refresh-removed
    python scripts/mutations.py --list

Each mutation replaces one piece of text in one file of a copy (git's files, so the working
tree is never touched) and runs the test files named for it, with CI=true (data tests fail
rather than skip) and the data of VSMATCH_DATA or ../shared/data. Those files are part of
the README's suite, so a mutation they catch fails the suite. The copy is first run as it is:
a mutation counts as caught only where its tests passed before. Exit status 1 when a
mutation survives. Not in CI: about 10 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Mutation:
    name: str
    what: str  # the fault, as the table says it
    file: str
    old: str
    new: str
    tests: tuple[str, ...]


MUTATIONS = [
    Mutation("scanline-off", "a stage turned off: the scanline optimisation",
             "vsmatch/level.py", "    scanline = cfg.scanline.enabled\n",
             "    scanline = False\n", ("tests/test_middlebury.py",)),
    Mutation("planes-off", "a stage turned off: the slanted planes",
             "vsmatch/pipeline.py",
             "    result.photometric = correction\n    _fit_planes(result, left, max_disp)\n",
             "    result.photometric = correction\n",
             ("tests/test_real_scenes.py",)),
    Mutation("tenth-worse", "a ceiling's figure about 10 % worse: every 400th pixel's "
             "disparity 9 px off (middlebury2's 2.52 -> ~2.77)",
             "vsmatch/pipeline.py", "    result = _with_confidence(result, left, max_disp)\n",
             "    result = _with_confidence(result, left, max_disp)\n"
             "    result.disparity.ravel()[::400] += 9\n",
             ("tests/test_middlebury.py",)),
    Mutation("alignment-reversed", "the temporal alignment reversed (memory moved against "
             "the image)", "vsmatch/temporal.py",
             "    dy, dx = image_shift(memory.grey, grey)\n",
             "    dy, dx = image_shift(memory.grey, grey)\n    dy, dx = -dy, -dx\n",
             ("tests/test_temporal.py",)),
    Mutation("exposure-refresh-removed", "the temporal mode's exposure refresh removed",
             "vsmatch/temporal.py",
             "    if max(abs(float(b.mean()) - float(a.mean())) for a, b in pairs) > "
             "cfg.exposure_jump:\n", "    if False:\n", ("tests/test_temporal.py",)),
    Mutation("collapse-refresh-removed", "the temporal mode's confidence-collapse refresh "
             "removed", "vsmatch/pipeline.py",
             "        if result.confidence.mean() >= cfg.temporal.collapse * "
             "memory.full_confidence:\n", "        if True:\n", ("tests/test_temporal.py",)),
    Mutation("coarse-look-removed", "the temporal mode's coarse look removed (a fast "
             "object lost)", "vsmatch/pipeline.py", "    if near.look is not None:\n",
             "    if False:\n", ("tests/test_temporal.py",)),
    Mutation("settle-removed", "what a moving object uncovers no longer settles (a trail)",
             "vsmatch/temporal.py", "    moved = changed if memory.settling is None else "
             "changed | (memory.settling > 0)\n", "    moved = changed\n",
             ("tests/test_temporal.py",)),
    Mutation("looked-curve-removed", "moved pixels judged on the last full search's cost "
             "curves (a view gone to noise in part stays confident)", "vsmatch/pipeline.py",
             "    if coarse_curve is not None:\n", "    if False:\n",
             ("tests/test_temporal.py",)),
    Mutation("same-file-refusal-removed", "a refusal removed: one file as both views",
             "vsmatch/io.py", "    if same_file(Path(left_path), Path(right_path)):\n",
             "    if False:\n", ("tests/test_io.py", "tests/test_cli.py")),
    Mutation("frames-over-input-refusal-removed", "a refusal removed: video --frames "
             "holding an input", "vsmatch/cli/video.py",
             "            if io.resolved(path).is_relative_to(root):\n",
             "            if False:\n", ("tests/test_output_safety.py", "tests/test_video.py")),
    Mutation("temporary-left", "a failed write's temporary file left behind",
             "vsmatch/io.py", "        if os.path.exists(tmp):\n            os.unlink(tmp)\n",
             "        pass\n", ("tests/test_io.py", "tests/test_output_safety.py")),
    Mutation("sighup-unhandled", "SIGHUP no longer handled as SIGTERM",
             "vsmatch/cli/console.py", '("SIGHUP", "hung up (the terminal closed)")',
             '("SIGHUP_", "hung up (the terminal closed)")', ("tests/test_signals.py",)),
    Mutation("range-end-warning-removed", "never silent: the warning of pixels piled at "
             "an end of the range removed", "vsmatch/cli/run.py",
             "    if piled is not None:\n", "    if False:\n",
             ("tests/test_range.py", "tests/test_range_checks.py")),
    Mutation("exposure-tails-merged", "the exposure map's levels beyond the matched ones "
             "merged onto its ends again (thin wires lost)", "vsmatch/photometric.py",
             "    out[high + 1:] = out[high] + np.arange(1, 256 - high)\n"
             "    out[:low] = out[low] - np.arange(low, 0, -1)\n",
             "", ("tests/test_photometric.py", "tests/test_thin_structures.py")),
    Mutation("documented-figure-drifts", "a documented figure drifts from its ceiling "
             "(the README's ETH3D 3.76 -> 3.66)", "README.md",
             "| ETH3D (9 scenes), nonocc bad 1.0 | **3.76** |",
             "| ETH3D (9 scenes), nonocc bad 1.0 | **3.66** |", ("tests/test_figures.py",)),
]


def copy_tree(target: Path) -> None:
    """Git's files of the checkout (tracked, and new ones not ignored), times kept."""
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                             "--exclude-standard"], cwd=REPO, capture_output=True,
                            check=True).stdout.decode().split("\0")
    for name in filter(None, listed):
        source = REPO / name
        if source.is_file():
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target / name)


def run_tests(copy: Path, tests: tuple[str, ...], env: dict, timeout: float
              ) -> tuple[int, str, float]:
    """pytest on ``tests`` in the copy: exit status, the first failure's line, seconds."""
    start = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p",
                               "no:cacheprovider", *tests], cwd=copy, env=env,
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return -1, f"timed out after {timeout:.0f} s", time.perf_counter() - start
    failed = [line for line in done.stdout.splitlines() if line.startswith(("FAILED",
                                                                            "ERROR"))]
    summary = failed[0] if failed else (done.stdout.strip().splitlines() or [""])[-1]
    return done.returncode, summary, time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", action="append", default=[], metavar="NAME",
                        help="run this mutation only (repeatable)")
    parser.add_argument("--list", action="store_true", help="list the mutations")
    parser.add_argument("--timeout", type=float, default=900,
                        help="seconds for one mutation's tests")
    args = parser.parse_args()
    if args.list:
        for m in MUTATIONS:
            print(f"{m.name:36s} {m.what}")
        return 0
    chosen = [m for m in MUTATIONS if not args.only or m.name in args.only]
    unknown = set(args.only) - {m.name for m in MUTATIONS}
    if unknown:
        parser.error(f"no mutation named {', '.join(sorted(unknown))} (see --list)")
    data = Path(os.environ.get("VSMATCH_DATA") or REPO.parent / "shared" / "data").resolve()
    with tempfile.TemporaryDirectory(prefix="vsmatch-mutations-") as folder:
        copy = Path(folder) / "vsmatch"
        copy_tree(copy)
        env = {**os.environ, "PYTHONPATH": str(copy), "CI": "true", "VSMATCH_DATA": str(data),
               "NUMBA_CACHE_DIR": str(Path(folder) / "numba-cache")}
        env.pop("VSMATCH_RECORD_FIGURES", None)
        found = subprocess.run([sys.executable, "-c", "import vsmatch; print(vsmatch.__file__)"],
                               cwd=copy, env=env, capture_output=True, text=True).stdout
        if not Path(found.strip()).is_relative_to(copy):
            print(f"the copy's vsmatch is not the one imported ({found.strip()})",
                  file=sys.stderr)
            return 2
        every = tuple(sorted({t for m in chosen for t in m.tests}))
        print(f"the copy as it is: {' '.join(every)} ...", flush=True)
        status, summary, seconds = run_tests(copy, every, env, args.timeout * 2)
        if status != 0:
            print(f"the unmutated copy fails ({summary}): fix that first", file=sys.stderr)
            return 2
        print(f"  passes ({summary}, {seconds:.0f} s)", flush=True)
        rows, survived = [], []
        for m in chosen:
            path = copy / m.file
            original, stat = path.read_text(), path.stat()
            if original.count(m.old) != 1:
                print(f"{m.name}: its text is not in {m.file} once: update the mutation",
                      file=sys.stderr)
                return 2
            path.write_text(original.replace(m.old, m.new))
            print(f"{m.name} ...", flush=True)
            try:
                status, summary, seconds = run_tests(copy, m.tests, env, args.timeout)
            finally:
                path.write_text(original)
                os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
            caught = status not in (0, 5, -1)  # 5: no tests ran
            if not caught:
                survived.append(m.name)
            first = summary.replace("|", "/")[:110]
            print(f"  {'caught' if caught else 'SURVIVED'}: {first} ({seconds:.0f} s)",
                  flush=True)
            rows.append(f"| {m.what} | `{m.file}` | {', '.join(m.tests)} | "
                        f"{'caught' if caught else '**survived**'}: {first} | {seconds:.0f} |")
    print("\n| fault | file | tests run | result (first failure) | s |")
    print("| --- | --- | --- | --- | --- |")
    print("\n".join(rows))
    if survived:
        print(f"\nsurvived: {', '.join(survived)}", file=sys.stderr)
    return 1 if survived else 0


if __name__ == "__main__":
    sys.exit(main())
