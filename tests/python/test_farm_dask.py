"""A Dask cluster on 127.0.0.1 (a scheduler and two worker processes started here, ended by their ids): the same
meshes as a local run, a worker killed while it works, a corrupt frame reported by name."""
import os
import signal
import subprocess
import threading
import time

import pytest

from meniscus import farm

from farm_support import (FRAMES, PIPELINE, end_process, environment, local_run, make_sequence, meshes, python_command,
                          use_farm_packages)

FARM_PYTHON = use_farm_packages()



@pytest.fixture(scope="module")
def python():
    return FARM_PYTHON


@pytest.fixture
def cluster(python, tmp_path):
    """A scheduler and two single-threaded workers without nannies (so that a killed worker stays dead)."""
    scheduler_file = tmp_path / "scheduler.json"
    dask = python.parent / "dask"
    logs = open(tmp_path / "cluster.log", "w")
    processes = []
    try:
        processes.append(subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                           "--scheduler-file", str(scheduler_file)], stdout=logs, stderr=logs,
                                          env=environment()))
        deadline = time.monotonic() + 60
        while not scheduler_file.exists():
            assert time.monotonic() < deadline and processes[0].poll() is None, (tmp_path / "cluster.log").read_text()
            time.sleep(0.1)
        for name in ("w1", "w2"):
            processes.append(subprocess.Popen([str(dask), "worker", "--scheduler-file", str(scheduler_file), "--name", name,
                                               "--nthreads", "1", "--no-nanny", "--host", "127.0.0.1", "--no-dashboard"],
                                              stdout=logs, stderr=logs, env=environment()))
        from distributed import Client
        client = Client(scheduler_file=str(scheduler_file), timeout=60)
        client.wait_for_workers(2, timeout=60)
        yield client, dict(zip(("w1", "w2"), processes[1:])), scheduler_file
        client.close()
    finally:
        for process in reversed(processes):
            end_process(process)
        logs.close()


def parameters_text(tmp_path, inputs):
    return farm.parameters_file_text({"particle_radius": 0.025, "cube_size": 1.0, "threads": 1}, input=str(inputs),
                                     output=str(tmp_path / "out" / "surface_{}.ply"))


def test_console_script_on_a_scheduler_matches_a_local_run(cli, python, cluster, tmp_path):
    client, _workers, scheduler_file = cluster
    reference = meshes(local_run(cli, tmp_path / "local"))
    inputs = make_sequence(tmp_path / "in")
    address = client.scheduler.address
    started = time.monotonic()
    result = subprocess.run([*python_command(python), "reconstruct", str(inputs), "-o", str(tmp_path / "out" / "surface_{}.ply"),
                             "-s", "1", "-e", "6", *PIPELINE, "--scheduler", address], capture_output=True, text=True,
                            timeout=300, env=environment())
    seconds = time.monotonic() - started
    assert result.returncode == 0, result.stderr
    assert meshes(tmp_path / "out") == reference and len(reference) == 6
    assert "6/6" in result.stderr  # the progress bar reached the end
    print(f"dask, 2 workers: 6 frames in {seconds:.1f} s")


def test_worker_killed_mid_work_its_frames_are_done_elsewhere(cli, cluster, tmp_path):
    client, workers, _ = cluster
    reference = meshes(local_run(cli, tmp_path / "local"))
    text = parameters_text(tmp_path, make_sequence(tmp_path / "in"))
    outcome = {}
    runner = threading.Thread(target=lambda: outcome.setdefault("run", farm.reconstruct_on_cluster(
        client, text, 1, 6, progress=False)))
    runner.start()
    killed = None
    deadline = time.monotonic() + 120
    while killed is None and time.monotonic() < deadline and runner.is_alive():
        # A worker that is running a task of ours: kill it (no nanny restarts it).
        for address, keys in client.processing().items():
            if keys:
                name = client.scheduler_info()["workers"].get(address, {}).get("name")
                if name in workers:
                    killed = name
                    os.kill(workers[name].pid, signal.SIGKILL)
                    workers[name].wait(timeout=10)
                    break
        time.sleep(0.01)
    runner.join(timeout=240)
    assert killed is not None and not runner.is_alive()
    run = outcome["run"]
    assert run.ok, (run.failed, run.errors)
    assert [r["frame"] for r in run.records] == list(FRAMES)  # every frame once
    assert meshes(tmp_path / "out") == reference
    assert len(client.scheduler_info()["workers"]) == 1


def test_corrupt_frame_is_reported_by_name_and_the_others_finish(cli, cluster, tmp_path):
    client, _workers, _ = cluster
    reference = meshes(local_run(cli, tmp_path / "local"))
    text = parameters_text(tmp_path, make_sequence(tmp_path / "in", corrupt={3}))
    run = farm.reconstruct_on_cluster(client, text, 1, 6, chunk_size=2, progress=False)
    assert list(run.failed) == [3] and "fluid_0003.vtk" in run.failed[3]
    produced = meshes(tmp_path / "out")
    assert sorted(produced) == [f"surface_{n:04d}.ply" for n in FRAMES if n != 3]
    assert all(produced[name] == reference[name] for name in produced)
