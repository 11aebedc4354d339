"""An earlier version of vsmatch against this one, alternating in one process.

A shared machine's load moves single runs by tens of per cent, and two benchmark runs one
after the other can land on different loads: this script times both versions and SGBM's
three modes in turn within every round, on the standard pairs (``vsmatch bench``'s), the
fastest of the rounds kept, and checks that the two versions give the same disparities
(where they should differ, ``--allow-changes`` reports the pairs instead of stopping).

The earlier version is taken from git (``REV``: a commit, tag or branch of this
repository) into a temporary folder as a package of another name, so both import side by
side; it compiles its kernels there once (a few minutes on 2 cores).

    python scripts/compare_versions.py REV [--config fast --config default]
        [--threads 2] [--rounds 3] [--data-root DIR] [--allow-changes]
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vsmatch import bench, pipeline, volumes  # noqa: E402
from vsmatch.peers import sgbm_matcher  # noqa: E402

#: The earlier version's package name beside ``vsmatch``.
OTHER = "vsmatch_before"


def import_revision(rev: str, folder: Path):
    """``vsmatch`` as it was at git revision ``rev``, unpacked into ``folder`` and imported
    as :data:`OTHER` (its modules import each other relatively)."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", rev,
                              "vsmatch"], check=True, capture_output=True).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        if hasattr(tarfile, "data_filter"):  # Python 3.12 and the backports
            tar.extractall(folder, filter="data")
        else:
            tar.extractall(folder)
    (folder / "vsmatch").rename(folder / OTHER)
    # Revisions before 2026-12-02 read their data files (bundled configs, weights) from the
    # package named "vsmatch", which is this one: pointed at their own.
    for module in (folder / OTHER).glob("*.py"):
        text = module.read_text()
        if 'resources.files("vsmatch")' in text:
            module.write_text(text.replace('resources.files("vsmatch")',
                                           "resources.files(__package__)"))
    sys.path.insert(0, str(folder))
    return (importlib.import_module(f"{OTHER}.pipeline"),
            importlib.import_module(f"{OTHER}.volumes"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev")
    parser.add_argument("--config", action="append")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--allow-changes", action="store_true")
    args = parser.parse_args()
    configs = args.config or ["fast", "default"]
    pairs = bench.standard_pairs(args.data_root)
    with tempfile.TemporaryDirectory() as tmp, bench.thread_count(args.threads):
        old_pipeline, old_volumes = import_revision(args.rev, Path(tmp))
        runs = {}
        for cfg in configs:
            runs[f"{args.rev[:10]} {cfg}"] = (old_pipeline.run, old_volumes, cfg)
            runs[f"now {cfg}"] = (pipeline.run, volumes, cfg)
        pools = {name: module.VolumePool() for name, (_, module, _) in runs.items()}
        best: dict[tuple[str, str], float] = {}
        changed = []
        for scene, _ in pairs:
            channels = 1 if scene.left.ndim == 2 else scene.left.shape[2]
            sgbm = {mode: sgbm_matcher(scene.max_disp, channels, min_disp=scene.min_disp,
                                       mode=value) for mode, value in bench.SGBM_MODES.items()}
            for matcher in sgbm.values():  # OpenCV's own first-call costs
                matcher.compute(scene.left, scene.right)
            for run, _, cfg in runs.values():  # the kernels this pair calls, compiled
                run(scene.left, scene.right, max_disp=scene.max_disp, min_disp=scene.min_disp,
                    config=cfg)
            out = {}
            for _ in range(args.rounds):
                for name, (run, module, cfg) in runs.items():
                    with module.reused(pools[name]):
                        start = time.perf_counter()
                        result = run(scene.left, scene.right, max_disp=scene.max_disp,
                                     min_disp=scene.min_disp, config=cfg)
                        seconds = time.perf_counter() - start
                    out[name] = result.disparity
                    best[scene.name, name] = min(best.get((scene.name, name), 1e9), seconds)
                for mode, matcher in sgbm.items():
                    start = time.perf_counter()
                    matcher.compute(scene.left, scene.right)
                    seconds = time.perf_counter() - start
                    best[scene.name, mode] = min(best.get((scene.name, mode), 1e9), seconds)
            for cfg in configs:
                if out[f"{args.rev[:10]} {cfg}"].tobytes() != out[f"now {cfg}"].tobytes():
                    changed.append(f"{scene.name} {cfg}")
            if changed and not args.allow_changes:
                sys.exit(f"the versions' disparities differ: {', '.join(changed)} "
                         f"(--allow-changes to time them anyway)")
    names = [*runs, *bench.SGBM_MODES]
    total = {name: sum(best[scene.name, name] for scene, _ in pairs) for name in names}
    threads = args.threads or "as set"
    print(f"threads {threads}, fastest of {args.rounds} alternating rounds, {len(pairs)} pairs; "
          + (f"disparities differ on {', '.join(changed)}" if changed
             else "the same disparities"))
    for name in names:
        print(f"  {name:18s} {total[name]:7.3f} s   x SGBM 5-dir "
              f"{total[name] / total['sgbm-5']:.2f}   x HH {total[name] / total['sgbm-hh']:.2f}"
              f"   x 3-way {total[name] / total['sgbm-3way']:.2f}")


if __name__ == "__main__":
    main()
