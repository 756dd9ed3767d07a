"""The grader where courses grade: a container run as root with Docker's defaults
(:mod:`docker_like`: no user namespaces, Docker's 14 capabilities, a private ``TMPDIR``), and
the Gradescope bundle in its ``/autograder`` layout after ``setup.sh``'s permission steps.

There the grader must pick the ``chroot`` level by itself, refuse anything weaker unless the
floor is lowered by name, grade an honest submission to full marks, and hold against a
submission that has already removed its audit hook (:mod:`hookless`): each attack of
``attacks/hookless_a1.py`` reports what it reached, and the test asserts it reached nothing,
earned nothing and left nothing running. The same attacks run at the bubblewrap level.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from autograder import jail, seccomp
from autograder.cli import main
from autograder.sandbox import isolation

REPO = Path(__file__).resolve().parents[1]
TESTS = REPO / "tests"
HARNESS = TESTS / "docker_like.py"
HONEST = (TESTS / "fixtures" / "a1" / "reference.py").read_text()
SEED = "container-seed-5b1e0c"

pytestmark = pytest.mark.skipif(
    sys.platform != "linux" or os.geteuid() != 0 or not seccomp.available()
    or shutil.which("unshare") is None,
    reason="the container harness needs Linux, root and libseccomp")


def in_container(*command: str, binds: tuple[str, ...] = (), timeout: float = 300,
                 **env: str) -> subprocess.CompletedProcess[str]:
    """``command`` run as Docker runs a container's root process (cwd: this checkout)."""
    options = [x for b in binds for x in ("--bind", b)]
    return subprocess.run([sys.executable, str(HARNESS), *options, "--", *command], cwd=REPO,
                          capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **env})


def processes_of(users: set[int]) -> list[str]:
    """The command lines of the processes of ``users`` now."""
    found = []
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                if entry.stat().st_uid in users:
                    found.append(Path(entry.path, "cmdline").read_bytes().decode(errors="replace"))
            except OSError:
                pass
    return found


def leased(path: Path) -> set[int]:
    """The user ids a hookless grader leased (tests/hookless.py's record)."""
    return {int(u) for u in path.read_text().split()} if path.exists() else set()


@pytest.fixture(scope="module")
def bundle(tmp_path_factory) -> Path:
    """The a1 bundle unpacked as Gradescope does, after setup.sh's own permission steps
    (step 4, run as written), standing in for ``/autograder``."""
    top = tmp_path_factory.mktemp("gradescope")
    seed = top / "seed.txt"
    seed.write_text(SEED + "\n")
    assert main(["gradescope", "a1", "--out", str(top / "a1.zip"), "--seed-file", str(seed)]) == 0
    root = top / "autograder"
    with zipfile.ZipFile(top / "a1.zip") as z:
        z.extractall(root / "source")
    for name in ("setup.sh", "run_autograder"):
        os.chmod(root / "source" / name, 0o755)
    shutil.copy2(root / "source" / "run_autograder", root / "run_autograder")
    setup = (root / "source" / "setup.sh").read_text()
    step = setup[setup.index('say "4/5'):setup.index('say "5/5')]
    commands = [line.strip()[len("run "):] for line in step.splitlines()
                if line.strip().startswith("run ")]
    assert any("go-rwx" in c for c in commands), "setup.sh's permission step changed"
    for command in commands:
        subprocess.run(["bash", "-c", command], check=True,
                       env={**os.environ, "ROOT": str(root), "SOURCE": str(root / "source")})
    assert os.stat(root).st_mode & 0o777 == 0o700
    return root


def class_folder(folder: Path, attack: str) -> Path:
    folder.mkdir()
    (folder / "ada.py").write_text(HONEST)
    (folder / "mallory.py").write_text(attack)
    (folder / "grace.py").write_text(HONEST)
    return folder


def attack(bundle_path: str) -> str:
    return ((TESTS / "attacks" / "hookless_a1.py").read_text()
            .replace("@CHECKOUT@", str(REPO)).replace("@BUNDLE@", bundle_path))


def reached(results: dict, function: str) -> list[dict]:
    """What each of ``function``'s cases says its attack reached."""
    found = []
    for t in results["tests"]:
        if t["extra_data"]["function"] == function:
            found += [json.loads(m) for m in re.findall(r"reached (\{[^}]*\})",
                                                          t["output"].replace("\\", ""))]
    return found


def check_the_class(out: Path, level: str, stderr: str, users: set[int]) -> None:
    """Honest rows keep full marks, the attacker earns nothing, reaches nothing, leaves
    nothing running, and the grader neither crashed nor printed a traceback."""
    assert "Traceback" not in stderr, stderr
    rows = {r["submission"]: r for r in csv.DictReader((out / "grades.csv").open())}
    assert {r["isolation"] for r in rows.values()} == {level}
    for honest in ("ada", "grace"):
        assert float(rows[honest]["score"]) == float(rows[honest]["max_score"]) > 0, honest
    assert float(rows["mallory"]["score"]) == 0
    results = json.loads((out / "mallory" / "results.json").read_text())
    secrets_ = reached(results, "quat_mul")
    assert secrets_ and all(r == {"imported_course": False, "listed": [], "read": []}
                            for r in secrets_), secrets_
    assert all(r == {"started": []} for r in reached(results, "quat_from_axis_angle"))
    # at bubblewrap, pid 1 is its own namespace's init (bwrap), which the kernel keeps from
    # any signal sent inside the namespace: kill() returns 0 and nothing happens
    own = {1} if level == "bubblewrap" else set()
    signalled = reached(results, "matrix_from_quat")
    assert signalled and all(set(r["signalled"]) <= own for r in signalled), signalled
    assert all(r["memory_mb"] <= 1024 for r in reached(results, "matrix_from_euler"))
    disk = reached(results, "quat_from_matrix")
    if level == "bubblewrap":  # its tmpfs is full at 16 MiB; /dev/shm is read-only
        assert disk and all(r["disk_mb"] <= 16 and r["shm_mb"] == 0 for r in disk)
    else:  # no tmpfs: the disk watch stopped it, and /dev/shm does not exist
        text = json.dumps(results)
        assert "wrote more than the 16 MB of files a submission may write" in text
    forged = [t for t in results["tests"] if t["extra_data"]["function"] == "slerp"]
    assert forged and all("result channel" in t["output"] for t in forged)
    assert SEED not in json.dumps(results) + stderr
    assert processes_of(users) == []


def test_a_container_grades_at_chroot_and_refuses_weaker_unless_asked(tmp_path):
    done = in_container(sys.executable, "-c", "from autograder.sandbox import probe; "
                        "p = probe(); print(p.level, '|', p.why_not_stronger)")
    assert done.returncode == 0, done.stderr
    level, why = done.stdout.strip().split(" | ", 1)
    assert level == "chroot" and "bwrap: No permissions to create new namespace" in why
    (tmp_path / "s.py").write_text(HONEST)
    args = ["-m", "autograder", "grade", "--assignment", "a1", str(tmp_path / "s.py"),
            "--out", str(tmp_path / "out"), "--isolation", "plain"]
    refused = in_container(sys.executable, *args)
    assert refused.returncode == 2 and not (tmp_path / "out").exists()
    assert "refusing to grade at isolation plain, below the floor chroot" in refused.stderr
    lowered = in_container(sys.executable, *args, "--min-isolation", "plain")
    assert lowered.returncode == 0, lowered.stderr
    assert "warning: isolation is weaker on this machine (plain)" in lowered.stderr


@pytest.mark.parametrize("level", ["chroot", "bubblewrap"])
def test_hookless_attacks_reach_nothing_and_earn_nothing(tmp_path, bundle, level):
    """A class of two honest submissions and one attacker, two at a time (the attacker
    always has a classmate running beside it), at each kernel level: in the container with
    the bundle bound at /autograder (chroot), and on this machine (bubblewrap)."""
    if level == "bubblewrap" and isolation() != "bubblewrap":
        pytest.skip("no bubblewrap here")
    seed = tmp_path / "seed"
    seed.write_text(SEED)
    folder = class_folder(tmp_path / "class", attack("/autograder"))
    out, leases = tmp_path / "out", tmp_path / "leases"
    args = [str(TESTS / "hookless.py"), "grade", "--assignment", "a1", str(folder), "--out",
            str(out), "--jobs", "2", "--seed-file", str(seed)]
    if level == "chroot":
        done = in_container(sys.executable, *args, binds=(f"{bundle}:/autograder",),
                            HOOKLESS_LEASES=str(leases),
                            # users no other test leases, so what is left running is its own
                            **{jail.UIDS_ENV: "61900-61949"})
        # one user per submission at a time (reused only once all its processes are gone)
        assert len(leased(leases)) >= 2
    else:
        done = subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True,
                              text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    # bubblewrap's children die with their PID namespace; the chroot level's users are checked
    check_the_class(out, level, done.stderr, leased(leases))


def test_the_bundle_as_shipped_grades_in_a_container(tmp_path, bundle):
    """After setup.sh's permission steps, inside the container: an honest submission gets
    full marks at the chroot level, and a thief reads neither the seed nor the bundle."""
    thief = attack("/autograder")
    for files, honest in (({"ada.py": HONEST}, True), ({"a1_rotations.py": thief}, False)):
        submission = bundle / "submission"
        shutil.rmtree(submission, ignore_errors=True)
        submission.mkdir()
        for name, text in files.items():
            (submission / name).write_text(text)
        done = in_container("/autograder/run_autograder", binds=(f"{bundle}:/autograder",),
                            AUTOGRADER_PYTHON=sys.executable)
        assert done.returncode == 0, done.stdout + done.stderr
        results = json.loads((bundle / "results" / "results.json").read_text())
        assert results["extra_data"]["isolation"] == "chroot", done.stdout
        total = sum(t["max_score"] for t in results["tests"])
        assert results["score"] == (total if honest else 0), done.stdout
        assert SEED not in json.dumps(results) + done.stdout


# those whose score a crash or a forged frame decides
SAME_SCORE = ("reference", "adv_exits", "adv_memory_bomb",
              "adv_garbage_bytes", "adv_huge_answer", "adv_wrong_types")


def test_one_score_per_submission_on_every_path(tmp_path):
    """The same files get the same scores on the local pool and on a cluster in the
    container (chroot), and on this machine's own level, and each row says its level."""
    folder = tmp_path / "class"
    folder.mkdir()
    fixtures = TESTS / "fixtures" / "a1"
    for name in SAME_SCORE:
        src = (fixtures / f"{name}.py").read_text().replace("@REPO@", str(REPO))
        if src.startswith("# extends: reference.py"):
            src = HONEST + "\n\n" + src
        (folder / f"{name}.py").write_text(src)
    seed = tmp_path / "seed"
    seed.write_text(SEED)
    grade = [sys.executable, "-m", "autograder", "grade", "--assignment", "a1", str(folder),
             "--seed-file", str(seed)]
    paths = {"here": ([*grade, "--jobs", "2", "--out", str(tmp_path / "here")], False),
             "pool": ([*grade, "--jobs", "2", "--out", str(tmp_path / "pool")], True),
             "cluster": ([*grade, "--scheduler", "local:2", "--out", str(tmp_path / "cluster")],
                         True)}
    scores = {}
    for path, (command, contained) in paths.items():
        done = (in_container(*command) if contained else
                subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300))
        assert done.returncode == 0, done.stderr
        rows = list(csv.DictReader((tmp_path / path / "grades.csv").open()))
        assert {r["isolation"] for r in rows} == {"chroot" if contained else isolation()}
        scores[path] = {r["submission"]: float(r["score"]) for r in rows}
    assert scores["here"] == scores["pool"] == scores["cluster"]
    assert scores["here"]["reference"] == 24 and scores["here"]["adv_exits"] < 24


def test_a_private_tmpdir_does_not_weaken_the_grader(tmp_path):
    """With TMPDIR a folder only root may enter (mktemp -d, PrivateTmp), the runtime used to
    be staged where bubblewrap's user could not read it, and the grader fell to plain. Its
    workspace is its own now: the strongest level still grades, to full marks."""
    private = tmp_path / "private"
    private.mkdir(mode=0o700)
    (tmp_path / "ada.py").write_text(HONEST)
    done = subprocess.run([sys.executable, "-m", "autograder", "grade", "--assignment", "a1",
                           str(tmp_path / "ada.py"), "--out", str(tmp_path / "out")],
                          cwd=REPO, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "TMPDIR": str(private)})
    assert done.returncode == 0, done.stderr
    row = next(csv.DictReader((tmp_path / "out" / "grades.csv").open()))
    assert row["isolation"] == isolation() and float(row["score"]) == 12
    assert "warning" not in done.stderr.replace("warning: no --seed-file", "")
