"""Where a match's system time goes: each stage's wall time, the pages it faulted and the
CPU seconds the operating system spent for it, in one fresh process.

A match at size touches hundreds of megabytes of fresh memory; mapping and zeroing it (and,
with transparent huge pages on ``madvise``, compacting memory for the 2 MB pages NumPy asks
for) is system time, which moves with the machine's memory rather than with the method
(docs/performance.md, "Memory the system maps"). Run it with ``NUMPY_MADVISE_HUGEPAGE=0``
to count 4 KB pages, one per 4 KB of fresh memory.

    python scripts/stage_faults.py [--config default] [--scale 2.05] [--scene Adirondack]
        [--data-root DIR]
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import resource
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from vsmatch import bench, datasets, level, pipeline, result, scale  # noqa: E402

#: Per stage: wall seconds, pages faulted, system seconds (stages inside others count in both).
TOTALS: dict[str, list[float]] = collections.defaultdict(lambda: [0.0, 0.0, 0.0])
_TIMED = result.timed


@contextlib.contextmanager
def _counted(seconds: dict[str, float], name: str):
    """``result.timed``, adding the stage's faults and system time to :data:`TOTALS`."""
    before, start = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    with _TIMED(seconds, name):
        yield
    after = resource.getrusage(resource.RUSAGE_SELF)
    total = TOTALS[name]
    total[0] += time.perf_counter() - start
    total[1] += after.ru_minflt - before.ru_minflt
    total[2] += after.ru_stime - before.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="default")
    parser.add_argument("--scale", type=float, default=2.05)
    parser.add_argument("--scene", default="Adirondack")
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    for module in (level, pipeline, scale):  # the modules that time stages
        module.timed = _counted
    [scene] = datasets.load_dataset("middlebury2014-quarter", args.data_root,
                                    names=[args.scene])
    left, right, _, _, max_disp = bench.upscaled_scene(scene, args.scale)
    crop = (slice(0, 48), slice(0, 64))  # load the kernels first
    pipeline.run(left[crop], right[crop], max_disp=16, config=args.config)
    TOTALS.clear()
    before, start = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    pipeline.run(left, right, max_disp=max_disp, config=args.config)
    after = resource.getrusage(resource.RUSAGE_SELF)
    print(f"{args.scene} x{args.scale} ({left.shape[1]}x{left.shape[0]}, {max_disp + 1} "
          f"disparities), {args.config}: {time.perf_counter() - start:.3f} s, "
          f"{after.ru_minflt - before.ru_minflt} pages faulted, "
          f"{after.ru_stime - before.ru_stime:.3f} s of system time")
    print(f"{'stage':<14}{'seconds':>9}{'faults':>10}{'system':>9}")
    for name, (seconds, faults, system) in sorted(TOTALS.items(), key=lambda kv: -kv[1][0]):
        print(f"{name:<14}{seconds:9.3f}{int(faults):>10}{system:9.3f}")


if __name__ == "__main__":
    main()
