"""What a sweep checks before and around its runs: scheduler, workers, the table's path, Ctrl-C, scene, inputs.

Issue 23, items 5, 7, 8, 9, 10 and 15. Every refusal is a ModelInputError (on the command
line one line `rbfmu: error: ...`) raised before any run; sweeps here run in this process
(`--workers 0`) with a handful of runs, and the one LocalCluster has a single worker.
"""

from __future__ import annotations

import os
import socket
import threading
import time
import zipfile

import numpy as np
import pandas as pd
import pytest

import fmu.sweep.engine as engine
from fmu.cli import main
from fmu.sweep.api import sweep
from fmu.sweep.engine import MAX_WORKERS_PER_CORE, SweepInterrupted, cluster_client, local_cores
from fmu.sweep.results import read_table
from modelsrc.errors import ModelInputError


def _one_line(capsys, *args: str) -> str:
    assert main(list(args)) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbfmu: error: ") and "\n" not in err, err
    return err


# --- item 5: a peer that accepts and stays silent -------------------------------------------------


@pytest.fixture
def silent_peer():
    """A TCP server on 127.0.0.1 that accepts every connection and never sends a byte."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    accepted: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                conn, _ = srv.accept()
            except OSError:  # closed at teardown
                return
            accepted.append(conn)

    threading.Thread(target=accept, daemon=True).start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}", accepted
    srv.close()
    for c in accepted:
        c.close()


def test_silent_scheduler_is_refused_within_the_connect_timeout(silent_peer, capsys, monkeypatch, tmp_path):
    """Today's main hung in distributed.Client() (killed at 200 s); the handshake is now
    bounded by CONNECT_TIMEOUT_S (1 s here) and the message says what went wrong."""
    address, accepted = silent_peer
    monkeypatch.setattr(engine, "CONNECT_TIMEOUT_S", 1.0, raising=False)  # absent before the fix
    outcome: list[object] = []

    def sweep_there() -> None:
        try:
            outcome.append(main(["sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--scheduler", address,
                                 "--out", str(tmp_path / "t.csv")]))  # fmt: skip
        except BaseException as exc:  # reported by the assertion below
            outcome.append(exc)

    tic = time.monotonic()
    thread = threading.Thread(target=sweep_there, daemon=True)
    thread.start()
    thread.join(15.0)
    assert not thread.is_alive(), "rbfmu sweep --scheduler still waits for a silent peer after 15 s"
    assert outcome == [2] and time.monotonic() - tic < 10.0
    err = capsys.readouterr().err
    assert f"--scheduler {address}: cannot connect to a dask scheduler there: no dask handshake within 1 s" in err
    assert accepted, "the peer was never connected to"
    assert not (tmp_path / "t.csv").exists()


# --- item 7: worker counts ------------------------------------------------------------------------


def test_absurd_worker_count_is_refused_before_anything_starts(capsys, tmp_path):
    """Today's main tried to start a million processes (1.6 GB after 3 min, no worker)."""
    limit = MAX_WORKERS_PER_CORE * local_cores()
    err = _one_line(capsys, "sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--workers", "1000000",
                    "--out", str(tmp_path / "t.csv"))  # fmt: skip
    assert f"--workers 1000000: at most {limit} worker processes ({MAX_WORKERS_PER_CORE} per core" in err
    with pytest.raises(ModelInputError, match=f"at most {limit} worker processes"):
        sweep("thrown_racket", {"mass": [0.3]}, workers=limit + 1, build_dir=tmp_path)


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--seed", "3"], "--seed draws the random runs of --sample; there is none"),
        (["--plot-figure", "E_kin"], "--plot-figure sets the map of --plot FILE.png"),
        (["--plot-axes", "mass"], "--plot-axes sets the map of --plot FILE.png"),
        (["--log-color"], "--log-color sets the map of --plot FILE.png"),
    ],
)
def test_settings_that_would_change_nothing_are_refused_before_any_run(capsys, tmp_path, monkeypatch, extra, needle):
    """On main before this test these four ran the sweep and said nothing: no random run to
    seed, no map to draw."""
    ran: list[object] = []
    monkeypatch.setattr("fmu.sweep.cli.sweep", lambda *a, **k: ran.append(a))
    err = _one_line(capsys, "sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--workers", "0",
                    "--out", str(tmp_path / "t.csv"), *extra)  # fmt: skip
    assert needle in err and ran == []


# --- item 8: the table's path, and Ctrl-C ---------------------------------------------------------


@pytest.mark.parametrize("target", ["adir.csv", "/proc/x.csv", "exists.csv"])
def test_unwritable_or_existing_out_is_refused_before_any_run(capsys, tmp_path, monkeypatch, target):
    """Today's main ran every run, then lost them to [Errno 21] (a directory adir.csv) or
    [Errno 2] (/proc), and silently replaced an existing file."""
    (tmp_path / "adir.csv").mkdir()
    (tmp_path / "exists.csv").write_text("keep me")
    ran: list[object] = []
    monkeypatch.setattr("fmu.sweep.cli.sweep", lambda *a, **k: ran.append(a))
    out = target if target.startswith("/") else str(tmp_path / target)
    err = _one_line(capsys, "sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--workers", "0", "--out", out)
    assert f"--out {out}: " in err and ran == []
    expected = {"adir.csv": "is a directory", "/proc/x.csv": "cannot write there", "exists.csv": "--overwrite"}
    assert expected[target] in err
    assert (tmp_path / "exists.csv").read_text() == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir.csv", "exists.csv"]  # no temporary file left


def test_overwrite_replaces_through_a_temporary_file(fmus, tmp_path, capsys):
    out = tmp_path / "t.csv"
    out.write_text("old")
    args = ["sweep", str(fmus["thrown_racket"]), "--param", "mass=0.3:0.4:2", "--workers", "0", "--no-progress",
            "--out", str(out), "--overwrite"]  # fmt: skip
    assert main(args) == 0
    assert len(read_table(out)) == 2
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_ctrl_c_keeps_the_completed_runs(fmus, tmp_path, capsys, monkeypatch):
    """Ctrl-C after two chunks of one run: the table holds those two runs and the message
    says so (today's main: a KeyboardInterrupt traceback and no table)."""
    import fmu.sweep.engine as eng

    real = eng.run_chunk
    calls = []

    def interrupted_third(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(eng, "run_chunk", interrupted_third)
    out = tmp_path / "t.csv"
    args = ["sweep", str(fmus["thrown_racket"]), "--param", "mass=0.3:0.4:5", "--workers", "0", "--chunk-size", "1",
            "--no-progress", "--out", str(out)]  # fmt: skip
    assert main(args) == 130
    err = capsys.readouterr().err
    assert f"interrupted: the 2 completed runs of 5 are saved in {out}" in err
    df = read_table(out)
    assert list(df.index) == [0, 1] and df["ok"].all()
    np.testing.assert_array_equal(df["mass"], [0.3, 0.325])
    # interrupted before the first run finished: nothing written, and it says so
    calls.clear()
    calls.extend([1, 1])
    out.unlink()
    assert main(args) == 130
    assert "interrupted before any run completed; nothing was saved" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_api_hands_the_completed_runs_over_with_the_interrupt(fmus, monkeypatch):
    import fmu.sweep.engine as eng

    real, calls = eng.run_chunk, []

    def interrupted_second(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(eng, "run_chunk", interrupted_second)
    with pytest.raises(SweepInterrupted) as stop:
        sweep(fmus["thrown_racket"], {"mass": [0.3, 0.4, 0.5]}, workers=0, chunk_size=1)
    assert isinstance(stop.value, KeyboardInterrupt)
    assert list(stop.value.table.index) == [0] and stop.value.table.attrs["planned_runs"] == 3


# --- item 9: the archive's scene --------------------------------------------------------------------


def test_an_fmu_with_another_scene_is_refused(fmus):
    """Today's main ran the spacecraft with the racket's experiment and labelled the table
    thrown_racket."""
    with pytest.raises(ModelInputError, match="was built from scene 'spacecraft_thruster', not from the given scene "
                                              "'thrown_racket'"):  # fmt: skip
        sweep(fmus["spacecraft_thruster"], {"w_body[1]": [0.1]}, scene="thrown_racket", workers=0)
    df = sweep(fmus["spacecraft_thruster"], {"w_body[1]": [0.1]}, scene="spacecraft_thruster", workers=0)
    assert df.attrs["scene"] == "spacecraft_thruster" and df["ok"].all()


# --- item 10: the LocalCluster listens on loopback only ---------------------------------------------


def _listening(pids: list[int]) -> list[tuple[str, int]]:
    """(address, port) of every listening TCP socket (IPv4 and IPv6) of the processes `pids`,
    from /proc/net/tcp{,6} and the processes' socket inodes."""
    inodes = set()
    for pid in pids:
        fd_dir = f"/proc/{pid}/fd"
        for fd in os.listdir(fd_dir):
            try:
                link = os.readlink(f"{fd_dir}/{fd}")
            except OSError:
                continue
            if link.startswith("socket:["):
                inodes.add(link[8:-1])
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with open(table) as f:
            for line in f.readlines()[1:]:
                cols = line.split()
                if cols[3] == "0A" and cols[9] in inodes:  # 0A: LISTEN
                    host, port = cols[1].split(":")
                    found.append((host, int(port, 16)))
    return found


LOOPBACK = {"0100007F", "00000000000000000000000001000000"}  # 127.0.0.1 and ::1 as /proc/net/tcp writes them


def test_local_cluster_listens_on_loopback_only():
    """Today's main put the dashboard on 0.0.0.0 (reachable from the network)."""
    psutil = pytest.importorskip("psutil", reason="psutil comes with distributed")
    with cluster_client(None, 1) as client:
        me = psutil.Process()
        pids = [me.pid, *(p.pid for p in me.children(recursive=True))]
        sockets = _listening(pids)
        assert client.dashboard_link.startswith("http://127.0.0.1:")
    assert len(sockets) >= 3  # scheduler, dashboard, the worker (and its nanny)
    assert all(host in LOOPBACK for host, _ in sockets), sockets


def test_dashboard_address_is_checked(capsys, tmp_path):
    err = _one_line(capsys, "sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--dashboard", "8787",
                    "--out", str(tmp_path / "t.csv"))  # fmt: skip
    assert "--dashboard '8787': give HOST:PORT" in err
    err = _one_line(capsys, "sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--dashboard", "127.0.0.1:0",
                    "--workers", "0", "--out", str(tmp_path / "t.csv"))  # fmt: skip
    assert "there is none with --workers 0" in err


# --- item 15: the API's own error for bad tables and archives ---------------------------------------


def test_api_errors_are_model_input_errors(fmus, tmp_path):
    """Today's main raised ValueError (2-D column), AttributeError (duplicate column) and
    zipfile.BadZipFile / KeyError (not an FMU)."""
    racket = fmus["thrown_racket"]
    with pytest.raises(ModelInputError, match="swept variable mass: every run needs one number, got a value of shape"):
        sweep(racket, pd.DataFrame({"mass": [np.array([0.3, 0.4]), np.array([0.5, 0.6])]}), workers=0)
    with pytest.raises(ModelInputError, match="swept variable mass: every run needs one number"):
        sweep(racket, {"mass": np.ones((2, 2))}, workers=0)
    with pytest.raises(ModelInputError, match="swept variable mass: the table of runs has two columns of that name"):
        sweep(racket, pd.DataFrame([[0.3, 0.4]], columns=["mass", "mass"]), workers=0)
    text = tmp_path / "text.fmu"
    text.write_text("not a zip archive")
    empty = tmp_path / "empty.fmu"
    zipfile.ZipFile(empty, "w").close()
    for path, why in ((text, "this file is not one"), (empty, "no modelDescription.xml")):
        for scene in (None, "thrown_racket"):
            with pytest.raises(ModelInputError, match=f"{path}: not an FMU .*{why}"):
                sweep(path, {"mass": [0.3]}, scene=scene, workers=0)
