"""One kernel of an earlier version against this one's, on the calls a match makes.

A whole match moves with the machine's load and holds a kernel's change among a dozen
others: this script records the calls one kernel gets while this version matches some of
the standard pairs (copies of their arguments), then times the earlier version's kernel
(``REV``, imported as ``compare_versions.py`` does) and this one's on those calls in turn,
the fastest of the rounds kept, after checking that both write the same bytes.

    python scripts/kernel_versions.py REV MODULE.KERNEL [--config default]
        [--scene Adirondack --scene cones ...] [--threads 1] [--rounds 5] [--data-root DIR]

``MODULE.KERNEL`` names a kernel of ``vsmatch._kernels`` (``scanline._ROWS[False]`` for
one a module keeps in a dict), e.g. ``disparity.winner_takes_all_both``.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from compare_versions import OTHER, import_revision  # noqa: E402
from vsmatch import bench, pipeline  # noqa: E402

#: Pairs recorded unless ``--scene`` names others: a small, a wide-range and a mid pair.
SCENES = ("cones", "Adirondack", "Vintage")


def kernel_of(package: str, name: str):
    """The kernel ``MODULE.KERNEL`` (or ``MODULE.TABLE[key]``) of ``package._kernels``,
    with its module and the attribute it is held under."""
    found = re.fullmatch(r"(\w+)\.(\w+)(?:\[(\w+)\])?", name)
    if found is None:
        sys.exit(f"not a kernel name: {name!r} (MODULE.KERNEL or MODULE.TABLE[key])")
    module_name, attribute, key = found.groups()
    module = importlib.import_module(f"{package}._kernels.{module_name}")
    value = getattr(module, attribute, None)
    if key is not None and value is not None:
        value = value.get({"True": True, "False": False}.get(key, key))
    if value is None:
        sys.exit(f"{package}._kernels has no kernel {name}")
    return module, attribute, key, value


def record(name: str, config: str, scenes: list[str], data_root: str | None) -> list[tuple]:
    """Copies of the arguments of every call of this version's kernel ``name`` while
    ``config`` matches ``scenes``."""
    module, attribute, key, kernel = kernel_of("vsmatch", name)
    calls = []

    def recording(*args):
        calls.append(tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args))
        return kernel(*args)

    holders = [m for m in list(sys.modules.values())
               if getattr(m, "__name__", "").startswith("vsmatch")]
    patched = [(m, a) for m in holders for a, v in list(vars(m).items()) if v is kernel]
    table = getattr(module, attribute) if key is not None else None
    for m, a in patched:
        setattr(m, a, recording)
    if table is not None:
        table_key = next(k for k, v in table.items() if v is kernel)
        table[table_key] = recording
    try:
        for scene, _ in bench.standard_pairs(data_root):
            if scene.name in scenes:
                pipeline.run(scene.left, scene.right, max_disp=scene.max_disp,
                             min_disp=scene.min_disp, config=config)
    finally:
        for m, a in patched:
            setattr(m, a, kernel)
        if table is not None:
            table[table_key] = kernel
    return calls


def timed(kernel, calls: list[tuple]) -> tuple[float, list]:
    """Seconds for ``kernel`` over all ``calls`` (on fresh copies of their arrays), and the
    arrays after the calls."""
    copies = [[a.copy() if isinstance(a, np.ndarray) else a for a in call] for call in calls]
    start = time.perf_counter()
    for args in copies:
        kernel(*args)
    return time.perf_counter() - start, copies


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev")
    parser.add_argument("kernel")
    parser.add_argument("--config", default="default")
    parser.add_argument("--scene", action="append")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--data-root", default=None)
    args = parser.parse_args()
    scenes = args.scene or list(SCENES)
    calls = record(args.kernel, args.config, scenes, args.data_root)
    if not calls:
        sys.exit(f"{args.config} made no call of {args.kernel} on {', '.join(scenes)}")
    with tempfile.TemporaryDirectory() as tmp, bench.thread_count(args.threads):
        import_revision(args.rev, Path(tmp))
        kernels = {args.rev[:10]: kernel_of(OTHER, args.kernel)[3],
                   "now": kernel_of("vsmatch", args.kernel)[3]}
        outputs = {name: timed(kernel, calls)[1] for name, kernel in kernels.items()}
        before, after = outputs.values()
        same = all(np.array_equal(a, b, equal_nan=True) for x, y in zip(before, after)
                   for a, b in zip(x, y) if isinstance(a, np.ndarray))
        best = {name: float("inf") for name in kernels}
        for _ in range(args.rounds):
            for name, kernel in kernels.items():
                best[name] = min(best[name], timed(kernel, calls)[0])
    first, now = best.values()
    print(f"{args.kernel}: {len(calls)} calls ({args.config} on {', '.join(scenes)}), "
          f"threads {args.threads}, fastest of {args.rounds} alternating rounds; "
          + ("the same outputs" if same else "the OUTPUTS DIFFER"))
    print(f"  {args.rev[:10]:10s} {first * 1e3:8.1f} ms")
    print(f"  {'now':10s} {now * 1e3:8.1f} ms   ({first / now:.2f}x)")


if __name__ == "__main__":
    main()
