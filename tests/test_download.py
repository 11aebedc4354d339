"""vsmatch datasets download, against a local HTTP server on 127.0.0.1 serving small zips
made here; never the internet."""

import functools
import http.server
import io as bytes_io
import threading
import zipfile

import pytest
from click.testing import CliRunner

from vsmatch.cli import main
from vsmatch.datasets import download

SCENES = ("Alpha", "Beta")


def make_archives(folder, resolution="Q", broken_gt=False, lacking=None):
    """MiddEval3-data-Q.zip and MiddEval3-GT0-Q.zip, with a test scene beside."""
    data, gt = bytes_io.BytesIO(), bytes_io.BytesIO()
    with zipfile.ZipFile(data, "w") as zd, zipfile.ZipFile(gt, "w") as zg:
        for scene in SCENES:
            base = f"MiddEval3/training{resolution}/{scene}/"
            for name in ("im0.png", "im1.png", "calib.txt"):
                zd.writestr(base + name, f"{scene} {name}")
            for name in ("disp0GT.pfm", "mask0nocc.png"):
                if name != lacking:
                    zg.writestr(base + name, f"{scene} {name}")
        zd.writestr(f"MiddEval3/test{resolution}/Gamma/im0.png", "test scene")
    (folder / f"MiddEval3-data-{resolution}.zip").write_bytes(data.getvalue())
    payload = b"this is not a zip" if broken_gt else gt.getvalue()
    (folder / f"MiddEval3-GT0-{resolution}.zip").write_bytes(payload)


@pytest.fixture
def server(tmp_path):
    """A local server over tmp_path/www; its request log is ``server.requests``."""
    root = tmp_path / "www"
    root.mkdir()
    requests = []

    class Handler(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

        def do_GET(self):
            requests.append(self.path)
            super().do_GET()

    httpd = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(Handler, directory=str(root)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    httpd.root, httpd.requests = root, requests
    httpd.url = f"http://127.0.0.1:{httpd.server_address[1]}"
    yield httpd
    httpd.shutdown()
    httpd.server_close()


def fetch(server, to, *extra):
    return CliRunner().invoke(main, ["-q", "datasets", "download", "middlebury2014",
                                     "--resolution", "Q", "--to", str(to),
                                     "--mirror", server.url, *extra])


def test_download_unpacks_the_training_scenes(server, tmp_path):
    make_archives(server.root)
    to = tmp_path / "data"
    result = fetch(server, to)
    assert result.exit_code == 0, result.output
    target = to / "middlebury2014-quarter"
    assert sorted(p.name for p in target.iterdir()) == list(SCENES)  # no test scene
    assert (target / "Beta" / "disp0GT.pfm").read_text() == "Beta disp0GT.pfm"
    assert sorted(p.name for p in to.iterdir()) == ["middlebury2014-quarter"]  # no cache left
    assert len(server.requests) == 2
    again = fetch(server, to)
    assert again.exit_code == 0 and len(server.requests) == 2  # nothing fetched again


def test_a_missing_archive_is_one_line_and_no_dataset(server, tmp_path):
    make_archives(server.root)
    (server.root / "MiddEval3-GT0-Q.zip").unlink()
    to = tmp_path / "data"
    result = fetch(server, to)
    assert result.exit_code == 1
    assert "HTTP 404" in result.output and len(result.output.strip().splitlines()) == 1
    assert not (to / "middlebury2014-quarter").exists()
    # The archive that did arrive is kept: a re-run fetches only the missing one.
    make_archives(server.root)
    before = len(server.requests)
    assert fetch(server, to).exit_code == 0
    assert server.requests[before:] == ["/MiddEval3-GT0-Q.zip"]
    assert (to / "middlebury2014-quarter" / "Alpha" / "mask0nocc.png").is_file()


def test_a_broken_archive_is_one_line_and_fetched_anew(server, tmp_path):
    make_archives(server.root, broken_gt=True)
    to = tmp_path / "data"
    result = fetch(server, to)
    assert result.exit_code == 1 and "not a readable zip archive" in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert not (to / "middlebury2014-quarter").exists()
    assert [p.name for p in to.iterdir() if not p.name.startswith(".")] == []


def test_an_archive_lacking_a_file_leaves_no_dataset(server, tmp_path):
    make_archives(server.root, lacking="mask0nocc.png")
    to = tmp_path / "data"
    result = fetch(server, to)
    assert result.exit_code == 1 and "lacks mask0nocc.png" in result.output
    assert not (to / "middlebury2014-quarter").exists()


def test_an_unreachable_server_is_one_line(tmp_path):
    import socket

    with socket.socket() as s:  # a port with nothing listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    result = CliRunner().invoke(main, ["-q", "datasets", "download", "middlebury2014",
                                       "--to", str(tmp_path), "--mirror",
                                       f"http://127.0.0.1:{port}"])
    assert result.exit_code == 1 and "download failed" in result.output
    assert len(result.output.strip().splitlines()) == 1


def test_kitti_explains_the_registration(tmp_path):
    result = CliRunner().invoke(main, ["datasets", "download", "kitti2015", "--to",
                                       str(tmp_path)])
    assert result.exit_code == 1 and "registration" in result.output
    assert str(tmp_path / "kitti2015") in result.output


def test_datasets_list_says_where_it_looks(tmp_path):
    result = CliRunner().invoke(main, ["datasets", "list", "--data-root", str(tmp_path)])
    assert result.exit_code == 0
    assert "middlebury2014-quarter" in result.output and "kitti2015" in result.output
    assert "datasets download middlebury2014 --resolution Q" in result.output


def test_archive_names():
    assert download.archive_names("H") == ["MiddEval3-data-H.zip", "MiddEval3-GT0-H.zip"]


def test_a_member_that_inflates_past_the_known_size_is_refused(server, tmp_path,
                                                                monkeypatch):
    make_archives(server.root)
    bomb = bytes_io.BytesIO()
    with zipfile.ZipFile(bomb, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("MiddEval3/trainingQ/Alpha/im0.png", b"\0" * (3 << 20))
    (server.root / "MiddEval3-data-Q.zip").write_bytes(bomb.getvalue())
    monkeypatch.setattr(download, "MAX_UNPACKED_MB", {"Q": 2})
    to = tmp_path / "data"
    result = fetch(server, to)
    assert result.exit_code == 1 and "more than the dataset's known size" in result.output
    assert not (to / "middlebury2014-quarter").exists()
    assert not [p for p in to.iterdir() if p.name.startswith(".middlebury")]


def test_stale_staging_is_removed_and_the_dataset_follows_the_umask(server, tmp_path):
    import os

    make_archives(server.root)
    to = tmp_path / "data"
    stale = to / ".middlebury2014-quarter.x8k2_a"  # what a killed unpack leaves
    (stale / "Alpha").mkdir(parents=True)
    old = os.umask(0o022)
    try:
        result = fetch(server, to)
    finally:
        os.umask(old)
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in to.iterdir()) == ["middlebury2014-quarter"]
    assert (to / "middlebury2014-quarter").stat().st_mode & 0o777 == 0o755


def test_datasets_list_names_one_data_root(tmp_path):
    result = CliRunner().invoke(main, ["datasets", "list", "--data-root", str(tmp_path)])
    roots = [line for line in result.output.splitlines() if line.startswith("data root")]
    assert roots == [f"data root: {tmp_path.resolve()} (--data-root or VSMATCH_DATA change it)"]


def test_a_failed_download_leaves_no_empty_folder(tmp_path):
    """The folder --to made and its empty .downloads/ cache go when nothing arrived."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    to = tmp_path / "new" / "data"
    result = CliRunner().invoke(main, ["-q", "datasets", "download", "middlebury2014",
                                       "--to", str(to), "--mirror",
                                       f"http://127.0.0.1:{port}"])
    assert result.exit_code == 1 and "download failed" in result.output
    assert list(tmp_path.iterdir()) == []


def test_a_mirror_folder_is_copied_from(tmp_path):
    """--mirror FOLDER (or file://FOLDER) showed pooch's "Unrecognized URL protocol
    'file'"; the archives are now copied from it, and a folder without them is named."""
    mirror = tmp_path / "archives"
    mirror.mkdir()
    make_archives(mirror)
    for given, to in ((str(mirror), tmp_path / "a"), (mirror.as_uri(), tmp_path / "b")):
        result = CliRunner().invoke(main, ["-q", "datasets", "download", "middlebury2014",
                                           "--resolution", "Q", "--to", str(to),
                                           "--mirror", given])
        assert result.exit_code == 0, result.output
        assert sorted(p.name for p in (to / "middlebury2014-quarter").iterdir()) == list(SCENES)
    result = CliRunner().invoke(main, ["datasets", "download", "middlebury2014", "--resolution",
                                       "Q", "--to", str(tmp_path / "c"), "--mirror",
                                       str(tmp_path / "nowhere")])
    assert result.exit_code == 1 and "no such folder" in result.output
    assert "Unrecognized" not in result.output and "Traceback" not in result.output
