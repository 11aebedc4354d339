"""The kernels' promise that no two array arguments overlap where one is written
(``vsmatch._kernels.WITHOUT_OVERLAP``: the serial kernels and the loop bodies are compiled
on it, and LLVM would reorder their reads and writes).

Every kernel the stages call from Python is wrapped to check its array arguments pairwise
while the first matches a config makes run (those ``python -m vsmatch.compilation``
records: colour and grey pairs, a range below 0, bands above a level down, a video
stream). An overlap fails the test unless both arguments are read only, as listed here.
"""

import inspect
import itertools
import sys

import numpy as np
import pytest

from vsmatch import compilation

#: Arguments that may share memory: both only read by the kernel (a curve's margin taken
#: for the raw margin where no scanline ran; the same view given as both views; a plane
#: fit before the last solved where the pixels it weighs are kept).
READ_TOGETHER = {
    "planes.fit_region_planes": {("kept", "wanted")},
    "confidence.pixel_terms": {("margin", "raw_margin")},
    "cost.view_terms": {("colour_l", "colour_r")},
    "photometric.matched_colours": {("left", "right")},
}


def _overlaps(dispatcher, args):
    """The pairs of ``args``' parameter names whose arrays share memory."""
    params = list(inspect.signature(dispatcher.py_func).parameters)
    arrays = [(params[i], a) for i, a in enumerate(args)
              if isinstance(a, np.ndarray) and a.size > 0]
    return {(p, q) for (p, a), (q, b) in itertools.combinations(arrays, 2)
            if np.may_share_memory(a, b) and np.shares_memory(a, b, max_work=10 ** 6)}


def _watch(monkeypatch, found, calls):
    """Wrap every kernel where the vsmatch modules hold it (module names and the kernels'
    own dicts), recording each call's overlapping arguments in ``found`` and its name in
    ``calls``."""
    dispatchers = compilation.kernel_dispatchers()
    names = {id(d): name for name, d in dispatchers.items()}
    wrappers = {}

    def wrapper(dispatcher):
        name = names[id(dispatcher)]

        def call(*args):
            calls.append(name)
            for pair in _overlaps(dispatcher, args):
                found.add((name,) + pair)
            return dispatcher(*args)
        return wrappers.setdefault(id(dispatcher), call)

    for module_name, module in list(sys.modules.items()):
        if not module_name.startswith("vsmatch") or module is None:
            continue
        for attr, value in list(vars(module).items()):
            if id(value) in names:
                monkeypatch.setattr(module, attr, wrapper(value))
            elif isinstance(value, dict):
                for key, item in list(value.items()):
                    if id(item) in names:
                        monkeypatch.setitem(value, key, wrapper(item))


@pytest.mark.parametrize("config", ["default", "fast", "accurate"])
def test_no_kernel_is_given_overlapping_arrays_it_writes(monkeypatch, config):
    found: set[tuple[str, str, str]] = set()
    calls: list[str] = []
    _watch(monkeypatch, found, calls)
    compilation.record_matches(config, bands=True)
    compilation.record_matches(config)
    compilation.record_stream(config)
    # Kernels called from Python, the scanline's (held in a dict) among them.
    assert len(set(calls)) > 20 and any(c.startswith("scanline.") for c in calls), calls
    unexpected = {f for f in found if (f[1], f[2]) not in READ_TOGETHER.get(f[0], set())}
    assert not unexpected, unexpected


def test_the_check_sees_an_output_over_its_input(monkeypatch):
    """A kernel handed its input as its output is caught (so the test above can fail)."""
    from vsmatch._kernels import planes

    found: set[tuple[str, str, str]] = set()
    _watch(monkeypatch, found, [])
    disp = np.arange(12, dtype=np.float32).reshape(3, 4)
    nan = np.full_like(disp, np.nan)
    planes.take_planes(disp, np.zeros(disp.shape, bool), nan, nan, np.float32(1),
                       np.float32(1), True, disp)
    assert ("planes.take_planes", "disp", "out") in found
