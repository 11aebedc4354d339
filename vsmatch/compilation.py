"""The kernels a config calls, compiled ahead of its first match, several at a time.

Numba compiles each kernel on its first call, one after another: the first match after an
install spent ~40 s there on 2 cores. Compiling is single-threaded, so several processes
that each compile a share of the kernels and write them to Numba's cache finish in about
the time of the largest share, and the match then loads them (milliseconds each). Which
kernels each bundled config calls, with which argument types, and how long each took to
compile is recorded in ``kernel_signatures.json``: ``python -m vsmatch.compilation
--write`` records it again (a test fails when a config calls a kernel it does not list).
A kernel the record does not list, or a share that fails, is compiled on its first call
as before: this only saves time.
"""

from __future__ import annotations

import functools
import importlib
import json
import os
import pkgutil
import subprocess
import sys
import time
from importlib import resources

import numpy as np

SIGNATURES_FILE = "kernel_signatures.json"
#: The record's entry of a config that is not bundled (a YAML file).
FALLBACK_CONFIG = "default"
#: What a config's record holds: the kernels of a whole-range match, and those that bands
#: above a level down (camera-size pairs, ``fast``) and a video stream's frames add.
USES = ("match", "bands", "stream")


def kernel_dispatchers() -> dict:
    """Every kernel of ``vsmatch._kernels`` by a stable name: ``module.attribute``, and
    ``module.attribute[key]`` for the kernels a module keeps in a dict (built by a factory,
    one per variant)."""
    from numba.core.caching import NullCache
    from numba.core.registry import CPUDispatcher

    from . import _kernels

    found = {}
    for info in pkgutil.iter_modules(_kernels.__path__):
        module = importlib.import_module(f"{_kernels.__name__}.{info.name}")
        for attr, value in sorted(vars(module).items()):
            entries = value.items() if isinstance(value, dict) else [(None, value)]
            for key, dispatcher in entries:
                # A loop body compiled with its kernel (``ROW_OPTIONS``) is not cached on
                # its own: not a kernel to compile ahead.
                if isinstance(dispatcher, CPUDispatcher) and dispatcher.__module__ == \
                        module.__name__ and not isinstance(getattr(dispatcher, "_cache", None),
                                                       NullCache):
                    name = f"{info.name}.{attr}" + ("" if key is None else f"[{key!r}]")
                    found[name] = dispatcher
    return found


def signatures_called() -> dict[str, list[str]]:
    """The argument types each kernel has been called with in this process (loaded from
    the cache or compiled), by :func:`kernel_dispatchers`' names."""
    return {name: sorted(str(sig) for sig in dispatcher.signatures)
            for name, dispatcher in kernel_dispatchers().items() if dispatcher.signatures}


def _recording_pairs():
    """The demo's synthetic pair, small, in colour and in grey (the types a first match
    meets), and its range: a scene as a camera sees one (textured surfaces at several
    depths), so that every step of a config runs, the planes too."""
    from .images import to_grey
    from .synthetic import make_pair

    pair = make_pair(width=160, height=120)
    colour = (pair.left, pair.right)
    grey = tuple(np.ascontiguousarray(to_grey(v).astype(np.uint8)) for v in colour)
    return colour, grey, pair.max_disp


def record_matches(config: str, bands: bool = False) -> None:
    """Run what a first use of ``config`` runs, on small pairs: a match of a colour and of
    a grey pair, each over a range from 0 and one from below 0; with ``bands``, searching
    bands above a level down (as camera-size pairs and ``fast`` do)."""
    from . import pipeline
    from .config import with_changes

    colour, grey, max_disp = _recording_pairs()
    cfg = config if not bands else with_changes(config, ["pyramid.max_row_cells=1024",
                                                         "pyramid.min_levels=1"])
    for left, right in (colour, grey):
        pipeline.run(left, right, max_disp=max_disp, config=cfg)
    pipeline.run(colour[0], colour[1], min_disp=-4, max_disp=max_disp, config=cfg)


def record_stream(config: str) -> None:
    """Run a short video stream with ``config``'s temporal mode: frames that hold still,
    then one where a block moved (the coarse look)."""
    from . import pipeline
    from .temporal import Temporal

    (left, right), _, max_disp = _recording_pairs()
    stream = Temporal()
    for frame in range(4):
        if frame == 3:
            left, right = left.copy(), right.copy()
            left[40:80, 50:90] = left[40:80, 10:50]
            right[40:80, 30:70] = right[40:80, 0:40]
        pipeline.run(left, right, max_disp=max_disp, config=config, temporal=stream)


def _types():
    from numba.core import types

    return {name: getattr(types, name) for name in dir(types)}


def _compile_share(share: list[tuple[str, list[str]]]) -> None:
    """Compile each ``(kernel name, [signature, ...])`` of ``share`` (into Numba's cache)."""
    dispatchers = kernel_dispatchers()
    names = _types()
    for name, signatures in share:
        dispatcher = dispatchers.get(name)
        if dispatcher is None:  # a record older than the code: compiled on its first call
            continue
        for text in signatures:
            dispatcher.compile(eval(text, {"__builtins__": {}}, names))  # noqa: S307


@functools.lru_cache(maxsize=None)
def load_record() -> dict:
    """``kernel_signatures.json``: ``{"configs": {name: {kernel: [signature, ...]}},
    "seconds": {kernel: compile seconds}}`` (read once; not to be changed)."""
    text = (resources.files(__package__) / SIGNATURES_FILE).read_text()
    return json.loads(text)


def kernels_for(config: str | None, bands: bool = True, stream: bool = False,
                also: tuple[str, ...] = ()) -> dict[str, list[str]]:
    """The kernels (and their signatures) ``config`` (a bundled name; else the default's)
    calls in a match, with ``bands`` where it searches bands above a level down, and with
    ``stream`` in a video stream's frames too; and those of a whole-range match of each
    config of ``also`` (finding a pair's range runs the default config's)."""
    record = load_record()["configs"]
    entries = [(record[name if name in record else FALLBACK_CONFIG], takes)
               for name, takes in [(config, (True, bands, stream))]
               + [(name, (True, False, False)) for name in also]]
    wanted: dict[str, set[str]] = {}
    for entry, takes in entries:
        for use, taken in zip(USES, takes):
            if taken:
                for kernel, signatures in entry[use].items():
                    wanted.setdefault(kernel, set()).update(signatures)
    return {kernel: sorted(signatures) for kernel, signatures in sorted(wanted.items())}


def searches_bands(cfg, shape: tuple[int, ...], min_disp: int, max_disp: int) -> bool:
    """Whether a match of a pair of ``shape`` over ``min_disp .. max_disp`` with ``cfg``
    (a Config) searches bands above a level down (the pipeline's own count of levels)."""
    from .scale import search_levels

    return search_levels(shape[1], shape[0], max_disp - min_disp, cfg) > 0


def shares(wanted: dict[str, list[str]], seconds: dict[str, float], workers: int
           ) -> list[list[tuple[str, list[str]]]]:
    """``wanted``'s kernels dealt to ``workers`` shares of about equal compile time (the
    longest first, each to the share with least so far). All signatures of one kernel go to
    one share: Numba keeps one cache index a kernel, which two processes would both write."""
    loads = [0.0] * workers
    dealt: list[list[tuple[str, list[str]]]] = [[] for _ in range(workers)]
    for kernel in sorted(wanted, key=lambda k: (-seconds.get(k, 1.0), k)):
        least = loads.index(min(loads))
        dealt[least].append((kernel, wanted[kernel]))
        loads[least] += seconds.get(kernel, 1.0)
    return [share for share in dealt if share]


def available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def compile_ahead(config: str | None, bands: bool = True, stream: bool = False,
                  workers: int | None = None, also: tuple[str, ...] = ()) -> float:
    """Compile the kernels ``config`` calls (:func:`kernels_for`), a share a core; the
    seconds it took. Call it where the cache is cold (``vsmatch._kernels.cache_is_cold``):
    with a warm one each share only loads its kernels."""
    return compile_kernels(kernels_for(config, bands, stream, also), workers)


def compile_kernels(wanted: dict[str, list[str]], workers: int | None = None) -> float:
    """Compile ``wanted`` (kernel name: signatures) into Numba's cache in ``workers``
    processes (default: one a core); the seconds it took. This process only waits: a
    signal reaches it at once (a kernel compiling here would hold it for seconds). A worker
    that fails is ignored (its kernels compile on their first call); an interrupted compile
    stops the workers with it."""
    start = time.perf_counter()
    dealt = shares(wanted, load_record()["seconds"], workers or available_cores())
    started = []
    try:
        for share in dealt:
            # A fresh interpreter each (a forked Numba runtime is not safe), the share on
            # its standard input.
            worker = subprocess.Popen([sys.executable, "-m", "vsmatch.compilation", "--share"],
                                      stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, text=True)
            started.append(worker)
            try:
                worker.stdin.write(json.dumps(share))
                worker.stdin.close()
            except OSError:  # it died at once: its kernels compile on their first call
                pass
        for worker in started:
            worker.wait()
    except BaseException:
        for worker in started:
            worker.kill()
            worker.wait()
        raise
    return time.perf_counter() - start


def _record_everything() -> dict:
    """Record each bundled config's kernels for each of :data:`USES`, each in a fresh
    process with an empty cache (the compile times are a cold start's); write nothing."""
    import tempfile

    from .config import bundled_config_names

    configs, seconds = {}, {}
    for config in bundled_config_names():
        entry: dict[str, dict[str, list[str]]] = {}
        for use in USES:
            with tempfile.TemporaryDirectory() as cache:
                env = {**os.environ, "NUMBA_CACHE_DIR": cache}
                out = subprocess.run([sys.executable, "-m", "vsmatch.compilation",
                                      "--child", config, use], env=env, check=True,
                                     capture_output=True, text=True).stdout
            child = json.loads(out.strip().splitlines()[-1])
            entry[use] = _beyond(child["signatures"], entry.get("match", {}))
            for kernel, value in child["seconds"].items():
                seconds[kernel] = round(max(seconds.get(kernel, 0.0), value), 2)
        configs[config] = entry
    return {"configs": configs, "seconds": dict(sorted(seconds.items()))}


def _beyond(called: dict[str, list[str]], match: dict[str, list[str]]
            ) -> dict[str, list[str]]:
    """What ``called`` holds that a whole-range ``match`` does not."""
    extra = {k: [s for s in v if s not in match.get(k, [])] for k, v in called.items()}
    return {k: v for k, v in extra.items() if v}


def _child(config: str, what: str) -> None:
    """In a fresh process: run ``what`` (one of :data:`USES`) with ``config``, timing each
    kernel's compilation; print the signatures and seconds as JSON."""
    from numba.core import event

    seconds: dict[str, float] = {}
    names = {id(d): n for n, d in kernel_dispatchers().items()}

    class Timer(event.Listener):
        def on_start(self, ev):
            self.started = getattr(self, "started", {})
            self.started[id(ev.data["dispatcher"])] = time.perf_counter()

        def on_end(self, ev):
            key = id(ev.data["dispatcher"])
            name = names.get(key)
            if name is not None:
                took = time.perf_counter() - self.started.pop(key)
                seconds[name] = seconds.get(name, 0.0) + took

    with event.install_listener("numba:compile", Timer()):
        record_matches(config)
        if what == "bands":
            record_matches(config, bands=True)
        if what == "stream":
            record_stream(config)
    print(json.dumps({"signatures": signatures_called(), "seconds": seconds}))


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        _child(argv[1], argv[2])
        return 0
    if argv[:1] == ["--share"]:  # a worker of compile_kernels
        _compile_share([(name, signatures) for name, signatures in json.load(sys.stdin)])
        return 0
    if argv[:1] != ["--write"] and argv[:1] != ["--print"]:
        print("usage: python -m vsmatch.compilation --write | --print", file=sys.stderr)
        return 2
    record = _record_everything()
    text = json.dumps(record, indent=1, sort_keys=True) + "\n"
    if argv[0] == "--print":
        print(text, end="")
        return 0
    path = resources.files(__package__) / SIGNATURES_FILE
    with open(str(path), "w") as fh:
        fh.write(text)
    total = sum(record["seconds"].values())
    print(f"wrote {path}: {len(record['seconds'])} kernels, {total:.0f} s to compile them all")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
