"""Where the kernels' time goes, instruction by instruction: Linux ``perf`` on the machine
code Numba made.

Numba's compiled code has no symbols ``perf`` can see. This script compiles the kernels
afresh (an empty ``NUMBA_CACHE_DIR``: a kernel loaded from the cache keeps no object
code), writes each one's object code to a folder and its functions' addresses to
``/tmp/perf-PID.map``, then matches a config over the standard pairs under ``perf record``
for ``--seconds``, and prints each function's share of the samples and, for the
``--top`` hottest, the instructions with most samples and those just before them (a
sample lands on the instruction after the one that waited). What it has found: loops left
scalar, scatters and gathers where a flat index Numba could not tell was >= 0 took a
wrap-around test (docs/performance.md, the planes' fit).

    python scripts/kernel_profile.py [CONFIG] [--threads 1] [--seconds 20] [--top 3]
        [--lines 30] [--show NAME ...] [--data-root DIR]

Needs ``perf`` (and the rights to run it: ``kernel.perf_event_paranoid`` <= 2), ``nm``
and ``objdump`` (binutils). Compiling afresh takes about a minute first.
"""

from __future__ import annotations

import argparse
import bisect
import collections
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _libraries(library, seen: dict, kernel: str) -> None:
    """``library`` and every library linked into it (a parallel kernel's loop body is one),
    each with the name of the first ``kernel`` found to hold it."""
    if id(library) in seen:
        return
    seen[id(library)] = (library, kernel)
    for linked in getattr(library, "_linking_libraries", ()):
        _libraries(linked, seen, kernel)


def map_functions(folder: Path) -> list[tuple[int, int, str, str, int]]:
    """Write every compiled kernel library's object code into ``folder`` and
    ``/tmp/perf-PID.map`` (``perf``'s map of code made at run time); return (address, size,
    name, object file, offset in it) of each function."""
    from vsmatch.compilation import kernel_dispatchers

    seen: dict = {}
    for kernel, dispatcher in kernel_dispatchers().items():
        for overload in dispatcher.overloads.values():
            _libraries(overload.library, seen, kernel)
    functions = []
    for number, (library, kernel) in enumerate(seen.values()):
        try:
            code = library._get_compiled_object()  # Numba's: the object code it linked
        except (RuntimeError, ValueError):  # loaded from a cache, or a wrapper: none kept
            continue
        path = folder / f"library{number}.o"
        path.write_bytes(code)
        symbols = subprocess.run(["nm", "-S", "--defined-only", str(path)], check=True,
                                 capture_output=True, text=True).stdout
        for line in symbols.splitlines():
            parts = line.split()
            if len(parts) == 4 and parts[2] in "Tt":
                offset, size, _, name = parts
                address = library.get_pointer_to_function(name)
                if address:
                    if "_parfor_gufunc_" in name:  # a parallel loop's body: its kernel's
                        name = f"{kernel} (its parallel loop)"
                    functions.append((address, int(size, 16), name, str(path),
                                      int(offset, 16)))
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as out:
        for address, size, name, _, _ in functions:
            out.write(f"{address:x} {size:x} {name}\n")
    return functions


def run_pairs(config: str, seconds: float, ready: Path, folder: Path) -> None:
    """The child: match the standard pairs once (compiling), map the code, tell the parent,
    then match them again and again for ``seconds``."""
    from vsmatch import bench, pipeline, volumes

    pairs = bench.standard_pairs()
    with volumes.reused():
        for scene, _ in pairs:
            pipeline.run(scene.left, scene.right, max_disp=scene.max_disp, config=config)
        functions = map_functions(folder)
        (folder / "functions.json").write_text(json.dumps(functions))
        ready.write_text(str(os.getpid()))
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            for scene, _ in pairs:
                pipeline.run(scene.left, scene.right, max_disp=scene.max_disp, config=config)


def short(name: str) -> str:
    """A mangled Numba name (``_ZN7vsmatch8_kernels6planes17fit_region_planesB...``) as
    ``planes.fit_region_planes``."""
    parts, at = [], name.find("_ZN") + 3
    while 0 < at < len(name) and name[at].isdigit():
        digits = re.match(r"\d+", name[at:]).group()
        at += len(digits)
        parts.append(name[at:at + int(digits)])
        at += int(digits)
    return ".".join(parts[2:4]) if parts[:2] == ["vsmatch", "_kernels"] else name[:80]


def report(samples_file: Path, folder: Path, top: int, lines: int,
           show: list[str] | None = None) -> None:
    """Print each mapped function's share of the recorded samples, then the hottest
    instructions of the ``top`` functions and of those whose name holds one of ``show``."""
    functions = json.loads((folder / "functions.json").read_text())
    script = subprocess.run(["perf", "script", "-i", str(samples_file), "-F", "ip"],
                            check=True, capture_output=True, text=True).stdout
    addresses = collections.Counter(int(word, 16) for word in script.split()
                                    if re.fullmatch(r"[0-9a-f]+", word))
    total = sum(addresses.values())
    starts = sorted(functions)
    per_function: collections.Counter = collections.Counter()
    per_offset: dict = collections.defaultdict(collections.Counter)
    keys = [f[0] for f in starts]
    for address, count in addresses.items():
        at = bisect.bisect_right(keys, address) - 1
        if at >= 0:
            start, size, name, path, offset = starts[at]
            if address < start + size:
                key = (name, path)
                per_function[key] += count
                per_offset[key][address - start + offset] += count
    print(f"{total} samples; the kernels' functions by share of them:")
    for (name, _), count in per_function.most_common(15):
        print(f"  {100 * count / total:5.1f} %  {short(name)}")
    listed = [key for key, _ in per_function.most_common(top)]
    listed += [key for key in per_function if key not in listed
               and any(part in short(key[0]) for part in show or ())]
    for key in listed:
        count = per_function[key]
        name, path = key
        listing = subprocess.run(["objdump", "-d", "--no-show-raw-insn", path], check=True,
                                 capture_output=True, text=True).stdout
        code = {}
        for line in listing.splitlines():
            found = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
            if found:
                code[int(found.group(1), 16)] = found.group(2)[:90]
        order = sorted(code)
        hot = [a for a, _ in per_offset[key].most_common(lines) if a in code]
        shown = sorted({order[i] for a in hot
                        for i in range(max(0, order.index(a) - 4), order.index(a) + 1)})
        print(f"\n{short(name)} ({100 * count / total:.1f} % of the samples): "
              "samples, offset, instruction")
        previous = None
        for address in shown:
            if previous is not None and order.index(address) != order.index(previous) + 1:
                print("   ...")
            print(f"{per_offset[key].get(address, 0):7d} {address:6x}  {code[address]}")
            previous = address


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default="default")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--top", type=int, default=3)
    parser.add_argument("--lines", type=int, default=30)
    parser.add_argument("--show", action="append", default=[],
                        help="also list the functions whose name holds this")
    parser.add_argument("--data-root", default=None)
    parser.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        import numba
        numba.set_num_threads(args.threads)
        run_pairs(args.config, args.seconds, Path(args.child[0]), Path(args.child[1]))
        return
    with tempfile.TemporaryDirectory() as work:
        folder, ready = Path(work), Path(work) / "ready"
        env = {**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache")}
        if args.data_root:
            env["VSMATCH_DATA"] = args.data_root
        # The matches go on a little longer than the recording, which ends first.
        child = subprocess.Popen([sys.executable, __file__, args.config, "--threads",
                                  str(args.threads), "--seconds", str(args.seconds + 5),
                                  "--child", str(ready), str(folder)], env=env)
        while not ready.exists():
            if child.poll() is not None:
                sys.exit("the matches stopped before their code was mapped")
            time.sleep(1)
        samples = folder / "perf.data"
        subprocess.run(["perf", "record", "-q", "-F", "2000", "-o", str(samples), "-p",
                        ready.read_text(), "--", "sleep", str(args.seconds)], check=True)
        child.wait()
        Path(f"/tmp/perf-{child.pid}.map").unlink(missing_ok=True)
        report(samples, folder, args.top, args.lines, args.show)


if __name__ == "__main__":
    main()
