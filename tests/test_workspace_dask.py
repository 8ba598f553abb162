"""Workspaces on Dask: a real run killed with SIGKILL and resumed, and a cluster of a scheduler and
two workers started here (loopback only), each compared with an uninterrupted in-process run."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from mcdm_pin import Robot
from mcdm_pin.workspace import Grid, RandomPoses, Setup, compute_workspace, open_workspace

from .conftest import REPO, TWO_LINK
from .test_workspace import assert_same_store

ENV = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))


def _kill_group(proc) -> None:
    """SIGKILL the process group this test started (the run and its Dask worker processes)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=30)


def test_a_run_killed_mid_way_and_resumed_ends_as_an_uninterrupted_run(tmp_path):
    store = tmp_path / "killed.zarr"
    args = [sys.executable, "-m", "mcdm_pin.cli", "workspace", str(TWO_LINK), "--case", "1",
            "--random", "1200", "--seed", "3", "--chunk", "60", "--out", str(store), "-q"]
    chunks = 20
    proc = subprocess.Popen(args + ["--scheduler", "local", "--workers", "1"], cwd=tmp_path, env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    done_dir = store / "chunk_done"
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and proc.poll() is None:
            if done_dir.is_dir() and len([p for p in done_dir.iterdir() if p.name.isdigit()]) >= 3:
                break
            time.sleep(0.02)
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(signal.SIGKILL)  # the run itself, mid-way, with no chance to clean up
        proc.wait(timeout=30)
    finally:
        _kill_group(proc)  # its orphaned worker processes
    flags = open_workspace(store)["chunk_done"].values
    missing = int((flags == 0).sum())
    assert 0 < missing < chunks, flags

    resumed = subprocess.run(args + ["--scheduler", "inline", "--resume"], cwd=tmp_path, env=ENV,
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"computed {missing} of {chunks} chunks" in resumed.stdout

    robot = Robot.load(TWO_LINK)
    reference = tmp_path / "reference.zarr"
    compute_workspace(robot, RandomPoses(robot, 1200, seed=3), reference, Setup(case=1), chunk=60,
                      scheduler="inline", progress=False)
    assert_same_store(open_workspace(store), open_workspace(reference))


@pytest.fixture
def cluster(tmp_path):
    """A Dask scheduler and two single-threaded workers on 127.0.0.1, started from another folder."""
    where = tmp_path / "cluster"
    where.mkdir()
    info = where / "scheduler.json"
    procs = []

    def start(*args):
        procs.append(subprocess.Popen([sys.executable, "-m", *args], cwd=where, env=ENV,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                      start_new_session=True))
    try:
        start("distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
              "--no-dashboard", "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(info))
        deadline = time.monotonic() + 60
        while not info.is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert info.is_file(), "the Dask scheduler did not start"
        address = re.search(r'"address": "(tcp://127\.0\.0\.1:\d+)"', info.read_text()).group(1)
        for _ in range(2):
            start("distributed.cli.dask_worker", address, "--nthreads", "1", "--host", "127.0.0.1",
                  "--no-dashboard", "--dashboard-address", "127.0.0.1:0", "--no-nanny")
        yield address
    finally:
        for p in procs:
            _kill_group(p)


def test_a_cluster_of_two_workers_gives_the_local_answers(cluster, tmp_path):
    # the robot is loaded from a copy that is deleted before the run: the workers get it as data
    copy = tmp_path / "robot"
    shutil.copytree(REPO / "robots", copy / "robots")
    shutil.copytree(REPO / "urdf", copy / "urdf")
    robot = Robot.load(copy / "robots" / "two_link_sr.yaml")
    shutil.rmtree(copy)
    poses = Grid(robot, {"q1_x": (-1.2, 1.2, 7), "q4_x": (-1.5, 1.5, 6)}, at={"q3_z": 0.1})
    setup = Setup(case=3, cones={"shoulder": 30.0}, margins=False)
    remote = compute_workspace(robot, poses, tmp_path / "cluster.zarr", setup, chunk=5,
                               scheduler=cluster, workers=2, progress=False)
    assert (remote.workers, remote.computed_chunks) == (2, 9)
    local = compute_workspace(robot, poses, tmp_path / "local.zarr", setup, chunk=5, scheduler="inline",
                              progress=False)
    a, b = open_workspace(remote.path), open_workspace(local.path)
    assert_same_store(a, b)
    status = a["status"].values
    assert {"optimal", "infeasible"} <= set(status)
    assert np.isfinite(a["f"].values[status == "optimal"]).all()
