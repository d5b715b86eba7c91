"""glint-ray: split a glint render into parts, run each as a Ray task, merge.

The driver stays thin: it splits the sample range, submits one Ray task per part (each
runs the ``glint`` binary: ``glint render SCENE --samples A..B -o part.exr``), lets Ray
retry a part whose worker died, shows progress, and calls ``glint merge``. Everything
that computes is in ``glint``, so a part renders the same on a laptop and on a cluster,
and the merge is bit-identical to a single render (see docs/distributed.md).
"""

from __future__ import annotations

import argparse
import ctypes
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import ray

#: Retries of a part whose worker process died (Ray's ``max_retries``).
WORKER_RETRIES = 3


class GlintFailed(Exception):
    """glint refused the part (exit code 1: bad scene or flags); retrying cannot help."""


class PartKilled(Exception):
    """The glint process of a part was killed by a signal; Ray retries the part."""


def _die_with_parent() -> None:
    """Runs in the glint child: a SIGKILL to the Ray worker then ends glint too (Linux)."""
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL)
    except OSError:
        pass


def _write_files(folder: str, prefix: str, datas) -> list[str]:
    """Writes each of ``datas`` to ``folder/PREFIXnnnnn.exr``; returns the paths in order."""
    files = []
    for k, data in enumerate(datas):
        files.append(os.path.join(folder, f"{prefix}{k:05}.exr"))
        with open(files[-1], "wb") as f:
            f.write(data)
    return files


def run_glint(glint: str, args: list[str], inputs: list[bytes] = ()) -> bytes:
    """Runs ``glint ARGS -o OUT`` in a fresh folder holding ``inputs`` as ``in*.exr``
    (appended to ARGS); returns OUT's bytes. Raises ``GlintFailed`` on exit code 1 and
    ``PartKilled`` on any other failure."""
    folder = tempfile.mkdtemp(prefix="glint-ray-")
    try:
        files = _write_files(folder, "in", inputs)
        out = os.path.join(folder, "out.exr")
        cmd = [glint, *args, *files, "-q", "-o", out]
        done = subprocess.run(cmd, capture_output=True, text=True, preexec_fn=_die_with_parent)
        # Exit code 1 is glint refusing its input: the same input fails the same way.
        if done.returncode == 1:
            raise GlintFailed(done.stderr.strip() or "glint exited with code 1")
        if done.returncode < 0:
            raise PartKilled(f"glint was killed by signal {-done.returncode}")
        if done.returncode != 0:
            raise PartKilled(f"glint exited with code {done.returncode}: {done.stderr.strip()}")
        with open(out, "rb") as f:
            return f.read()
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@ray.remote(num_cpus=1, max_retries=WORKER_RETRIES, retry_exceptions=[PartKilled])
def render_part(glint: str, args: list[str], samples: tuple[int, int]) -> bytes:
    """Renders samples ``samples[0]..samples[1]`` with ``glint``; returns the part file."""
    return run_glint(glint, ["render", *args, "--samples", f"{samples[0]}..{samples[1]}"])


@ray.remote(num_cpus=1, max_retries=WORKER_RETRIES, retry_exceptions=[PartKilled])
def merge_group(glint: str, *parts: bytes) -> bytes:
    """Merges part files into one part (``glint merge --part``), on a worker."""
    return run_glint(glint, ["merge", "--part"], list(parts))


def split(spp: int, parts: int) -> list[tuple[int, int]]:
    """``parts`` sample ranges tiling ``0..spp``, as even as integers allow."""
    edges = [spp * i // parts for i in range(parts + 1)]
    return [(a, b) for a, b in zip(edges, edges[1:]) if a < b]


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="glint-ray", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene as parts on Ray and merge them")
    r.add_argument("scene", help="the scene file (workers must see it at this path)")
    r.add_argument("--spp", type=int, required=True, help="samples per pixel in total")
    r.add_argument("--parts", type=int, default=64, help="number of parts (Ray tasks)")
    r.add_argument("-o", "--output", required=True, help="merged image, .png or .exr")
    r.add_argument("--address", help="a Ray cluster, e.g. ray://head:10001 (default: start Ray on this machine)")
    r.add_argument("--glint", help="the glint binary (default: `glint` on PATH)")
    r.add_argument("--threads", type=int, default=1, help="threads of each part (and CPUs it asks Ray for)")
    r.add_argument("--width", type=int, help="image width (overrides the scene's camera)")
    r.add_argument("--height", type=int, help="image height (overrides the scene's camera)")
    r.add_argument("--seed", type=int, help="random seed (overrides the scene's settings)")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a setting, as in glint")
    r.add_argument("--merge-group", type=int, default=32,
                   help="with more parts than this, workers merge groups of this many first")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress lines")
    a = p.parse_args(argv)
    if a.spp < 1 or a.parts < 1 or a.merge_group < 2:
        p.error("--spp and --parts must be at least 1, --merge-group at least 2")
    return a


def glint_args(a: argparse.Namespace) -> list[str]:
    """The scene and its overrides, as every part passes them to glint."""
    args = [os.path.abspath(a.scene), "--set", f"pixel_samples={a.spp}", "--threads", str(a.threads)]
    for flag in ("width", "height", "seed"):
        if getattr(a, flag) is not None:
            args += [f"--{flag}", str(getattr(a, flag))]
    for kv in a.set:
        args += ["--set", kv]
    return args


def render(a: argparse.Namespace) -> int:
    glint = a.glint or shutil.which("glint")
    if glint is None:
        print("error: no glint binary on PATH (give one with --glint)", file=sys.stderr)
        return 1
    local_glint = shutil.which(glint) or glint
    if a.address is None:
        glint = os.path.abspath(local_glint)
    ranges = split(a.spp, a.parts)
    # Parts cancelled after a failure would each print a traceback at exit.
    os.environ.setdefault("RAY_IGNORE_UNHANDLED_ERRORS", "1")
    started = time.monotonic()
    ray.init(address=a.address, logging_level="ERROR", log_to_driver=False, include_dashboard=False)
    start = time.monotonic()
    args = glint_args(a)
    task = render_part.options(num_cpus=a.threads)
    pending = {task.remote(glint, args, r): i for i, r in enumerate(ranges)}
    done: dict[int, ray.ObjectRef] = {}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        i = pending.pop(ready[0])
        try:
            # Only to see whether it failed: the bytes stay in Ray's object store.
            ray.get(ready[0])
        except (GlintFailed, ray.exceptions.RayError) as e:
            for ref in pending:
                ray.cancel(ref, force=True)
            report(e, f"part {i} (samples {ranges[i][0]}..{ranges[i][1]})")
            return 1
        done[i] = ready[0]
        if not a.quiet:
            print(
                f"glint-ray: {len(done)}/{len(ranges)} parts done ({time.monotonic() - start:.1f} s)",
                file=sys.stderr,
            )
    refs = [done[i] for i in sorted(done)]
    if len(refs) > a.merge_group:
        # Merge groups on the workers first, so the driver merges few files.
        groups = [refs[k : k + a.merge_group] for k in range(0, len(refs), a.merge_group)]
        merges = [merge_group.remote(glint, *g) for g in groups]
        try:
            ray.get(merges)
        except (GlintFailed, ray.exceptions.RayError) as e:
            report(e, "a group merge")
            return 1
        refs = merges
    code = merge_locally(local_glint, [ray.get(r) for r in refs], a.output, a.quiet)
    if not a.quiet:
        print(
            f"glint-ray: Ray started in {start - started:.1f} s, {len(ranges)} parts rendered "
            f"and merged in {time.monotonic() - start:.1f} s",
            file=sys.stderr,
        )
    return code


def report(e: Exception, what: str) -> None:
    """Prints why the job failed: glint's own message, or which task ran out of retries."""
    if isinstance(e, GlintFailed):
        # glint's own message, which names the file and field.
        cause = getattr(e, "cause", e)
        print(cause.args[0] if cause.args else str(cause), file=sys.stderr)
    else:
        print(f"error: {what} failed after {WORKER_RETRIES} retries: {e}", file=sys.stderr)


def merge_locally(glint: str, parts: list[bytes], output: str, quiet: bool) -> int:
    """``glint merge`` of the part files into the image ``output``; its exit code."""
    folder = tempfile.mkdtemp(prefix="glint-ray-merge-")
    try:
        files = _write_files(folder, "part", parts)
        merge = [glint, "merge", *files, "-o", output]
        if quiet:
            merge.append("-q")
        return subprocess.run(merge).returncode
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    a = parse_args(argv)
    try:
        return render(a)
    finally:
        if ray.is_initialized():
            ray.shutdown()


if __name__ == "__main__":
    sys.exit(main())
