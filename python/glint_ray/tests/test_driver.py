"""The driver on Ray started on this machine: 8 parts with one worker killed mid-part give
the bytes of a single render; a bad scene fails the job at once with glint's message."""

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from glint_ray import split

REPO = Path(__file__).resolve().parents[3]
SCENE = REPO / "scenes" / "cornell_box.ron"
SIZE = ["--width", "160", "--height", "120"]
# Enough samples that each of the 8 parts runs long enough to be caught and killed (at
# 32, a part took about 25 ms on a quiet machine and the killer mostly missed them all).
SPP = 256


def glint_binary():
    """$GLINT, else target/release/glint of $CARGO_TARGET_DIR or the repository, else PATH."""
    candidates = [os.environ.get("GLINT")]
    target = os.environ.get("CARGO_TARGET_DIR", str(REPO / "target"))
    candidates.append(os.path.join(target, "release", "glint"))
    candidates.append(shutil.which("glint"))
    for c in candidates:
        if c and os.access(c, os.X_OK):
            return c
    pytest.skip("no glint binary: build it with cargo build --release or set GLINT")


def driver(glint, scene, out, *extra):
    cmd = [sys.executable, "-m", "glint_ray.driver", "render", str(scene), "--spp", str(SPP),
           "--parts", "8", "-o", str(out), "--glint", glint, *SIZE, *extra]
    return subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)


def glint_parts_of(scene):
    """(pid, parent pid) of each running `glint render` of a part of `scene`."""
    found = []
    for pid in os.listdir("/proc"):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read().split(b"\0")
            with open(f"/proc/{pid}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if b"render" in cmd and b"--samples" in cmd and str(scene).encode() in cmd:
            found.append((int(pid), ppid))
    return found


def test_split_tiles_the_samples():
    assert split(10, 4) == [(0, 2), (2, 5), (5, 7), (7, 10)]
    assert split(3, 8) == [(0, 1), (1, 2), (2, 3)]


def test_a_killed_worker_is_retried_and_the_result_is_bit_identical(tmp_path):
    glint = glint_binary()
    scene = tmp_path / "scene.ron"
    shutil.copy(SCENE, scene)
    single = tmp_path / "single.exr"
    subprocess.run([glint, "render", str(scene), "--set", f"pixel_samples={SPP}", *SIZE,
                    "-q", "-o", str(single)], check=True)
    merged = tmp_path / "merged.exr"
    # Groups of 4: the workers merge two groups, the driver merges those two.
    job = driver(glint, scene, merged, "--merge-group", "4")
    killed = []

    def kill_one_worker():
        while job.poll() is None and not killed:
            running = glint_parts_of(scene)
            if running:
                # Let the part get going, then kill the Ray worker that runs it.
                time.sleep(0.01)
                pid, worker = running[0]
                if os.path.exists(f"/proc/{pid}"):
                    os.kill(worker, signal.SIGKILL)
                    killed.append(worker)
            time.sleep(0.005)

    killer = threading.Thread(target=kill_one_worker)
    killer.start()
    _, stderr = job.communicate(timeout=600)
    killer.join()
    assert job.returncode == 0, stderr
    assert killed, "no part was running long enough to be killed"
    assert merged.read_bytes() == single.read_bytes()


def test_a_bad_scene_fails_the_job_at_once_with_glints_message(tmp_path):
    glint = glint_binary()
    scene = tmp_path / "bad.ron"
    scene.write_text(SCENE.read_text().replace("fov_y: 40.0", "fov_y: -40.0"))
    job = driver(glint, scene, tmp_path / "out.exr")
    _, stderr = job.communicate(timeout=600)
    assert job.returncode == 1, stderr
    expected = f"error: {scene}: camera: fov_y: must be in (0, 180) degrees, got -40"
    assert stderr.count(expected) == 1, stderr
    assert "Traceback" not in stderr, stderr
    assert not (tmp_path / "out.exr").exists()
