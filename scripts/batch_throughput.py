"""Throughput of vsmatch batch on one machine: one process, --jobs N, and a local Dask
cluster (--scheduler local:N), alternating over a few rounds on the same pairs.

The pairs are a recording made in a temporary folder from the KITTI 2015 frames under
the data root (image_2/ + image_3/, each frame repeated ``--copies`` times), matched with
the range found per frame, as `vsmatch batch` does by default. Prints each mode's fastest
round, and the time to the first completed pair (start-up: processes, cluster, kernels).

    python scripts/batch_throughput.py [--data-root DIR] [--workers 2] [--rounds 3]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from vsmatch import batch, datasets
from vsmatch.config import load_config
from vsmatch.executors import make_executor


def make_recording(data_root, folder: Path, copies: int) -> None:
    training = datasets.dataset_folder("kitti2015", data_root) / "training"
    for side in ("image_2", "image_3"):
        (folder / side).mkdir(parents=True)
        for k in range(copies):
            for frame in sorted((training / side).glob("*_10.png")):
                shutil.copy(frame, folder / side / f"{k}_{frame.name}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--copies", type=int, default=4)
    args = parser.parse_args()
    modes = {"one process": dict(jobs=1), f"--jobs {args.workers}": dict(jobs=args.workers),
             f"--scheduler local:{args.workers}": dict(scheduler=f"local:{args.workers}")}
    config = load_config(None)
    best: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp) / "recording"
        make_recording(args.data_root, source, args.copies)
        for _ in range(args.rounds):
            for name, mode in modes.items():
                out = Path(tmp) / "out"
                shutil.rmtree(out, ignore_errors=True)
                out.mkdir()
                jobs, _ = batch.find_pairs(source, out, max_disp=None, suffix=".pfm")
                start = time.perf_counter()
                first: list[float] = []
                with make_executor(**mode) as executor:
                    failures = batch.run_batch(
                        jobs, config, executor=executor,
                        on_done=lambda job, outcome: first or first.append(time.perf_counter()))
                total = time.perf_counter() - start
                assert not failures, failures
                print(f"{name:<22}{len(jobs)} pairs in {total:6.2f} s "
                      f"(first after {first[0] - start:.2f} s)", flush=True)
                if name not in best or total < best[name][0]:
                    best[name] = (total, first[0] - start)
    print("\nfastest of each:")
    for name, (total, first) in best.items():
        print(f"{name:<22}{total:6.2f} s, {len(jobs) / total:.2f} pairs/s, "
              f"first pair after {first:.2f} s")


if __name__ == "__main__":
    main()
