"""The kernels compiled ahead of a first match (vsmatch.compilation)."""

import json
import os
import subprocess
import sys

import pytest

from vsmatch import compilation
from vsmatch.config import bundled_config_names


def _called(config: str, what: str) -> dict[str, list[str]]:
    """The kernels (and signatures) ``what`` (one of ``compilation.USES``) of ``config``
    calls, run in a fresh process (this one's kernels hold every signature the tests
    met)."""
    out = subprocess.run([sys.executable, "-m", "vsmatch.compilation", "--child", config,
                          what], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])["signatures"]


@pytest.mark.parametrize("config, use", [(name, "match") for name in bundled_config_names()]
                         + [("default", "bands"), ("fast", "bands"), ("default", "stream")])
def test_the_record_lists_every_kernel_a_config_calls(config, use):
    """Each bundled config's first matches call the kernels the record lists for it, with
    the same argument types, no more and no fewer (and bands and a stream what it lists
    beyond those): a kernel added or retyped without ``python -m vsmatch.compilation
    --write`` fails here (it would compile on its first call, alone, after the others)."""
    entry = compilation.load_record()["configs"][config]
    called = _called(config, use)
    if use != "match":
        called = compilation._beyond(called, entry["match"])
    assert called == entry[use]


def test_a_match_without_bands_compiles_fewer_kernels():
    plain = compilation.kernels_for("default", bands=False)
    assert set(plain) < set(compilation.kernels_for("default"))
    assert set(compilation.kernels_for("default")) < set(
        compilation.kernels_for("default", stream=True))
    assert "scanline._ROWS[True]" not in plain


def test_bands_are_searched_as_the_pipeline_decides():
    from vsmatch.config import load_config

    default, fast = load_config("default"), load_config("fast")
    assert not compilation.searches_bands(default, (375, 450, 3), 0, 59)  # cones
    assert compilation.searches_bands(fast, (375, 450, 3), 0, 59)  # fast: a level down
    assert compilation.searches_bands(default, (1984, 2872, 3), 0, 291)  # 4x Adirondack
    assert not compilation.searches_bands(fast, (375, 450, 3), 0, 15)  # too few to halve


def test_a_config_file_takes_the_defaults_kernels():
    assert compilation.kernels_for("/somewhere/mine.yaml") == compilation.kernels_for("default")


def test_shares_keep_each_kernel_whole_and_even():
    wanted = {"a": ["s1", "s2"], "b": ["s1"], "c": ["s1"], "d": ["s1"]}
    seconds = {"a": 6.0, "b": 4.0, "c": 3.0, "d": 2.0}
    dealt = compilation.shares(wanted, seconds, 2)
    assert dealt == [[("a", ["s1", "s2"]), ("d", ["s1"])], [("b", ["s1"]), ("c", ["s1"])]]
    assert compilation.shares(wanted, seconds, 8) == [[(k, wanted[k])] for k in "abcd"]
    assert compilation.shares({}, seconds, 2) == []


def test_every_kernel_recorded_exists():
    kernels = compilation.kernel_dispatchers()
    record = compilation.load_record()
    for config, entry in record["configs"].items():
        assert set(entry) == set(compilation.USES), config
        for wanted in entry.values():
            assert set(wanted) <= set(kernels), config
            assert set(wanted) <= set(record["seconds"]), config


_SECOND_PROCESS = """
import json, sys
from numba.core import event
from vsmatch import compilation
wanted = json.loads(sys.argv[1])
compiled = []
class Seen(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].__name__)
    def on_end(self, ev):
        pass
with event.install_listener("numba:compile", Seen()):
    compilation._compile_share(list(wanted.items()))
print(json.dumps(compiled))
"""


def test_kernels_compiled_ahead_in_two_processes_load_from_the_cache(tmp_path):
    """Two small kernels compiled ahead, one here and one in a spawned process, into an
    empty cache: a later process loads both and compiles nothing."""
    record = compilation.kernels_for("default", bands=False)
    wanted = {name: record[name]
              for name in ("photometric.matched_colours", "photometric.map_colours")}
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    first = ("import json, sys\nfrom vsmatch import compilation\n"
             "compilation.compile_kernels(json.loads(sys.argv[1]), workers=2)\n")
    subprocess.run([sys.executable, "-c", first, json.dumps(wanted)], env=env, check=True)
    assert any(tmp_path.rglob("*.nbi"))
    out = subprocess.run([sys.executable, "-c", _SECOND_PROCESS, json.dumps(wanted)],
                         env=env, check=True, capture_output=True, text=True).stdout
    assert json.loads(out.strip().splitlines()[-1]) == []
    # The same two into another empty cache without compiling ahead: the check can fail.
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "empty")
    out = subprocess.run([sys.executable, "-c", _SECOND_PROCESS, json.dumps(wanted)],
                         env=env, check=True, capture_output=True, text=True).stdout
    assert {"matched_colours", "map_colours"} <= set(json.loads(out.strip().splitlines()[-1]))


def test_also_adds_another_configs_whole_range_match():
    """Finding a range runs the default config's match: ``also`` adds its kernels (and no
    band or stream kernels of its own)."""
    both = compilation.kernels_for("census", bands=False, also=("default",))
    for kernel, signatures in compilation.kernels_for("default", bands=False).items():
        assert set(signatures) <= set(both[kernel])
    for kernel, signatures in compilation.kernels_for("census", bands=False).items():
        assert set(signatures) <= set(both[kernel])
    assert "scanline.rows_over_lanes" not in both
