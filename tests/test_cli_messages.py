"""What the command line says: unexpected errors in one line, verbosity flags, a cold
kernel cache announced."""

import os
from pathlib import Path

import pytest

from cli_helpers import files_in, invoke, one_line_error
from conftest import random_pair

from vsmatch import pipeline


def test_unexpected_errors_are_one_line_and_debug_shows_them(pair_files, tmp_path,
                                                            monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(pipeline, "run", broken)
    args = ["run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8]
    line = one_line_error(invoke(*args), unexpected=True)
    assert "vsmatch run: unexpected ZeroDivisionError: boom" in line
    assert isinstance(invoke("--debug", *args).exception, ZeroDivisionError)
    assert isinstance(invoke(*args, env={"VSMATCH_DEBUG": "1"}).exception, ZeroDivisionError)
    assert files_in(tmp_path) == ["l.png", "r.png"]


def test_verbose_and_quiet_after_the_command(pair_files, tmp_path):
    loud = invoke("run", *pair_files, "-o", tmp_path / "v.pfm", "--max-disp", 8, "-v")
    assert loud.exit_code == 0 and "seconds:" in loud.output
    quiet = invoke("run", *pair_files, "-o", tmp_path / "q.pfm", "--max-disp", 8, "-q")
    assert quiet.exit_code == 0 and quiet.output == ""


def test_a_cold_kernel_cache_is_announced(pair_files, tmp_path, monkeypatch):
    from vsmatch import _kernels

    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 8)
    assert result.exit_code == 0 and "compiling the kernels once" in result.output
    monkeypatch.undo()
    assert "compiling" not in invoke("run", *pair_files, "-o", tmp_path / "e.pfm",
                                     "--max-disp", 8).output


@pytest.mark.parametrize("config, bands", [("default", False), ("fast", True)])
def test_a_cold_cache_compiles_what_the_match_will_call(tmp_path, rng, monkeypatch, config,
                                                        bands):
    """On a cold cache `run` compiles the config's kernels ahead, those of bands only where
    the pair will search them (``fast`` a level down at every size, ``default`` not on a
    small pair)."""
    import cv2

    from vsmatch import _kernels, compilation

    pair_files = [tmp_path / "l.png", tmp_path / "r.png"]
    for path, view in zip(pair_files, random_pair(rng, height=48, width=96, shift=5)):
        cv2.imwrite(str(path), view)
    asked = []
    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    monkeypatch.setattr(compilation, "compile_ahead",
                        lambda *args, **kwargs: asked.append((args, kwargs)) or 0.0)
    result = invoke("run", *pair_files, "-o", tmp_path / "d.pfm", "--max-disp", 24,
                    "--config", config)
    assert result.exit_code == 0 and asked == [((config, bands, False), {"also": ()})]


def test_a_cold_cache_compiles_before_the_range_is_found(data_dir, tmp_path, monkeypatch):
    """Finding the range runs a match of the default config's: on a cold cache the kernels
    are compiled ahead before it (they were compiled one after another there, and the
    compiling ahead after it found a warm cache), bands included, the range not known yet;
    a swapped pair is refused before any compiling."""
    from vsmatch import _kernels, compilation

    asked = []
    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    monkeypatch.setattr(compilation, "compile_ahead",
                        lambda *args, **kwargs: asked.append((args, kwargs)) or 0.0)
    cones = data_dir / "middlebury2" / "cones"
    swapped = invoke("run", cones / "imR.png", cones / "imL.png", "-o", tmp_path / "s.pfm",
                     "--config", "fast")
    assert swapped.exit_code == 1 and asked == []
    result = invoke("run", cones / "imL.png", cones / "imR.png", "-o", tmp_path / "d.pfm",
                    "--config", "fast")
    assert result.exit_code == 0
    assert asked[0] == (("fast", True, False), {"also": ("default",)})


def test_cache_is_cold_looks_where_numba_caches(tmp_path):
    """Numba caches under NUMBA_CACHE_DIR (or ~/.cache/numba for a read-only install):
    the check asks Numba where, and finds a kernel cached there."""
    import subprocess
    import sys
    script = ("from vsmatch._kernels import cache_is_cold\n"
              "from vsmatch._kernels.aggregate import sum_along_arms\n"
              "print(cache_is_cold(), sum_along_arms._cache.cache_path)\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def ask():
        out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                             text=True, check=True).stdout.split()
        return out[0] == "True", Path(out[1])

    cold, folder = ask()
    assert cold and folder.is_relative_to(tmp_path / "numba")
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"aggregate.sum_over_arms-24.{tag}.nbi").write_bytes(b"")
    assert ask()[0] is False


def test_demo_announces_the_first_compilation(tmp_path, monkeypatch):
    from vsmatch import _kernels

    monkeypatch.setattr(_kernels, "cache_is_cold", lambda: True)
    result = invoke("demo", "-o", tmp_path / "demo")
    assert result.exit_code == 0 and "compiling the kernels once" in result.output
