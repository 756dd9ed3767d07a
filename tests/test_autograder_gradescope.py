"""The Gradescope bundle in its real layout.

Each assignment's zip is built once, unpacked into a temporary root that stands in for
``/autograder`` (``source/`` = the zip, ``run_autograder`` copied beside it, as Gradescope
does), checked by ``setup.sh`` in its dry-run mode, then ``run_autograder`` grades honest,
mutant and hostile submissions, a notebook, an empty folder, a syntax error and a folder of
several files; every results.json must follow Gradescope's documented format. The grader's
Python is a fresh virtual environment holding numpy alone: what ``setup.sh`` installs.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from autograder.cli import main
from autograder.gradescope_json import code_block, markdown_text
from autograder.gradescope_schema import problems

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures"
SEED = "gs-test-seed-3f9a1c77e2b04d6d"  # what a hostile submission must never see

pytestmark = pytest.mark.skipif(sys.platform != "linux" or shutil.which("bash") is None,
                                reason="Gradescope's images are Linux; the scripts are bash")


@pytest.fixture(scope="module")
def numpy_python(tmp_path_factory) -> Path:
    """A virtual environment of this Python whose only package is this numpy."""
    import numpy

    base = tmp_path_factory.mktemp("numpy-only")
    subprocess.run([sys._base_executable, "-m", "venv", "--without-pip", str(base / "venv")],
                   check=True)
    site = base / "site"
    site.mkdir()
    here = Path(numpy.__file__).resolve().parents[1]
    for entry in here.iterdir():
        if entry.name == "numpy" or entry.name.startswith(("numpy.libs", "numpy-")):
            (site / entry.name).symlink_to(entry)
    purelib = subprocess.run([str(base / "venv/bin/python"), "-c",
                              "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, check=True).stdout.strip()
    (Path(purelib) / "numpy_only.pth").write_text(f"{site}\n")
    return base / "venv" / "bin" / "python"


@pytest.fixture(scope="module")
def roots(tmp_path_factory, numpy_python):
    """assignment -> a built, unpacked and dry-run-checked root standing in for /autograder."""
    made = {}
    seed_file = tmp_path_factory.mktemp("seed") / "seed.txt"
    seed_file.write_text(SEED + "\n")

    def root_of(key: str) -> Path:
        if key not in made:
            top = tmp_path_factory.mktemp(f"gradescope-{key}")
            bundle = top / f"{key}_autograder.zip"
            assert main(["gradescope", key, "--out", str(bundle), "--seed-file",
                         str(seed_file)]) == 0
            root = top / "autograder"
            with zipfile.ZipFile(bundle) as z:
                z.extractall(root / "source")
                modes = {i.filename: i.external_attr >> 16 for i in z.infolist()}
            for name in ("setup.sh", "run_autograder"):  # zipfile does not restore modes
                assert modes[name] & 0o777 == 0o755
                os.chmod(root / "source" / name, 0o755)
            assert modes["seed"] & 0o777 == 0o400
            shutil.copy2(root / "source" / "run_autograder", root / "run_autograder")
            out = subprocess.run(["bash", str(root / "source" / "setup.sh")],
                                 env=_env(root, numpy_python, AUTOGRADER_SETUP_DRY_RUN="1"),
                                 capture_output=True, text=True)
            assert out.returncode == 0, out.stdout + out.stderr
            assert "nothing was installed" in out.stdout
            assert f"{key} (" in out.stdout and "numpy" in out.stdout  # the check_install step
            assert not (root / "venv").exists()
            made[key] = root
        return made[key]

    return root_of


def _env(root: Path, python: Path, **extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("AUTOGRADER_", "PYTHON", "VIRTUAL_ENV"))}
    return {**env, "AUTOGRADER_ROOT": str(root), "AUTOGRADER_PYTHON": str(python), **extra}


def grade(root: Path, python: Path, files: dict[str, str | bytes], metadata: dict | None = None,
          **env: str) -> tuple[dict, str]:
    """Put ``files`` in ``root/submission`` and run ``run_autograder`` as Gradescope does; the
    results (checked against the schema) and the log."""
    out = run_autograder(root, python, files, metadata, **env)
    assert out.returncode == 0, out.stdout + out.stderr
    text = (root / "results" / "results.json").read_text()
    results = json.loads(text)
    assert problems(results) == [], text
    assert SEED not in text and SEED not in out.stdout + out.stderr
    _check_conventions(results)
    return results, out.stdout


def run_autograder(root: Path, python: Path, files: dict[str, str | bytes],
                   metadata: dict | None = None, **env: str) -> subprocess.CompletedProcess:
    """``run_autograder`` run as Gradescope runs it on ``files``."""
    submission = root / "submission"
    shutil.rmtree(submission, ignore_errors=True)
    submission.mkdir()
    for name, content in files.items():
        path = submission / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    meta = root / "submission_metadata.json"
    meta.unlink(missing_ok=True)
    if metadata is not None:
        meta.write_text(json.dumps(metadata))
    return subprocess.run([str(root / "run_autograder")], cwd=root, capture_output=True,
                          text=True, env=_env(root, python, **env), timeout=300)


def _check_conventions(results: dict) -> None:
    """What our results always say, beyond the schema."""
    assert results["output_format"] == "md" and results["stdout_visibility"] == "hidden"
    assert isinstance(results["output"], str) and results["output"]
    assert results["execution_time"] >= 0
    for t in results["tests"]:
        assert {"name", "score", "max_score", "output", "visibility"} <= set(t)
        assert t["output_format"] == "md" and 0 <= t["score"] <= t["max_score"]
        assert t["extra_data"]["execution_time"] >= 0
    if results["tests"]:
        assert results["score"] == pytest.approx(sum(t["score"] for t in results["tests"]))


def fixture(key: str, name: str, root: Path) -> str:
    """A fixture's source (after the reference if it ``extends`` it); ``@REPO@`` (what a
    hostile one tries to read) is the bundle."""
    src = (FIXTURES / key / f"{name}.py").read_text().replace("@REPO@", str(root / "source"))
    if src.startswith("# extends: reference.py"):
        src = (FIXTURES / key / "reference.py").read_text() + "\n\n" + src
    return src


def expected_key(key: str, name: str) -> str:
    return re.search(r"# expect: (\S+)", (FIXTURES / key / f"{name}.py").read_text()).group(1)


@pytest.mark.parametrize("key", ["a1", "a2", "a3"])
def test_bundle_layout_and_honest_reference(roots, numpy_python, key):
    root = roots(key)
    source = root / "source"
    assert (source / "setup.sh").exists() and (source / "run_autograder").exists()
    assert (source / "seed").read_text().strip() == SEED
    assert (source / "autograder" / "assignments" / f"{key}.py").exists()
    assert not [p for p in source.rglob("*.py")
                if p.parent.name == "assignments" and re.fullmatch(r"a\d", p.stem)
                and p.stem != key]
    assert not list(source.glob("tests")) and not list(source.rglob("*.ipynb"))
    env = dict(line.split("=", 1) for line in (source / "bundle.env").read_text().split())
    import numpy

    assert env == {"ASSIGNMENT": key, "NUMPY_VERSION": numpy.__version__,
                   "PYTHON_VERSION": f"{sys.version_info.major}.{sys.version_info.minor}"}

    results, log = grade(root, numpy_python, {"my submission.py": fixture(key, "reference",
                                                                          root)})
    required = [t for t in results["tests"] if "bonus" not in t["name"]]
    assert required and all(t["status"] == "passed" for t in required)
    assert results["score"] >= sum(t["max_score"] for t in required)
    assert {t["visibility"] for t in results["tests"]} == {"visible", "after_published"}
    assert "Graded my submission.py." in results["output"].replace("\\", "")
    assert f"assignment {key}; isolation " in log  # the log names the run
    # what setup.sh makes true, the grader makes true on every run too
    assert stat.S_IMODE((root / "source" / "seed").stat().st_mode) == 0o400
    assert stat.S_IMODE(root.stat().st_mode) == 0o700


@pytest.mark.parametrize(("key", "name"), [
    ("a1", "mutant_mul_reversed"), ("a1", "mutant_axis_degrees"),
    ("a2", "mutant_fk_reversed_product"), ("a3", "mutant_ccd_effector_pivot"),
])
def test_mutants_lose_points_and_are_named(roots, numpy_python, key, name):
    root = roots(key)
    results, _ = grade(root, numpy_python, {"solution.py": fixture(key, name, root)})
    function, mistake = expected_key(key, name).split(":")
    assert 0 < results["score"] < sum(t["max_score"] for t in results["tests"])
    named = [t for t in results["tests"] if t["extra_data"]["misconception"] == mistake]
    assert named and all(t["extra_data"]["function"] == function for t in named)
    if any(t["visibility"] == "visible" for t in named):  # the summary names what shows
        assert "Likely mistakes" in results["output"]
        assert f"`{function}()`" in results["output"]
    hidden_only = [t for t in results["tests"] if t["visibility"] == "after_published"]
    assert all(t["name"] not in results["output"] for t in hidden_only)


SEED_THIEF = '''\
import numpy as np

_os = np.__builtins__["__import__"]("os")  # past the static import check


def _steal():
    found = []
    for path in ("@ROOT@/source/seed", "/autograder/source/seed", "@ROOT@/source/bundle.env"):
        try:
            with open(path) as f:
                found.append(f.read())
        except BaseException as exc:
            found.append(type(exc).__name__)
    found.append(str(_os.environ.get("AUTOGRADER_SEED")))
    return "|".join(found)


def quat_mul(a, b):
    s = _steal()
    print(s)
    raise RuntimeError("stolen: " + s)


quat_from_axis_angle = matrix_from_quat = quat_from_matrix = matrix_from_euler = slerp = (
    lambda *args: quat_mul(None, None))
'''


@pytest.mark.parametrize("isolation", ["bubblewrap", "chroot"])
def test_a_seed_thief_reads_nothing_and_scores_nothing(roots, numpy_python, isolation):
    root = roots("a1")
    from autograder.sandbox import isolation as strongest

    if isolation == "bubblewrap" and strongest() != "bubblewrap":
        pytest.skip("no bubblewrap here")
    if isolation == "chroot" and os.geteuid() != 0:
        pytest.skip("the chroot level needs a root grader, as on Gradescope")
    results, log = grade(root, numpy_python,
                         {"thief.py": SEED_THIEF.replace("@ROOT@", str(root))},
                         AUTOGRADER_ISOLATION=isolation)
    assert results["score"] == 0
    assert results["extra_data"]["isolation"] == isolation
    assert "stolen: " in json.dumps(results)  # it ran, and what it got was refusals
    if isolation == "chroot" and os.geteuid() == 0:
        # without the audit hook, the submission's user still cannot reach the bundle
        python = shutil.which("python3", path="/usr/bin:/bin")
        seed = root / "source" / "seed"
        raw = subprocess.run([python, "-I", "-c", f"print(open({str(seed)!r}).read())"],
                             user=65534, group=65534, capture_output=True, text=True)
        assert raw.returncode != 0 and "PermissionError" in raw.stderr
        assert SEED not in raw.stdout


@pytest.mark.parametrize(("key", "name"), [
    ("a1", "adv_snooping"), ("a1", "adv_reads_reference"), ("a2", "adv_reads_the_files"),
    ("a3", "adv_ik_returns_input"),
])
def test_hostile_fixtures_score_nothing(roots, numpy_python, key, name):
    """Nothing for what the hostile code does (a fixture that extends the reference keeps
    the points of the reference's functions it leaves alone)."""
    root = roots(key)
    results, _ = grade(root, numpy_python, {f"{name}.py": fixture(key, name, root)})
    own = (FIXTURES / key / f"{name}.py").read_text()
    if own.startswith("# extends: reference.py"):
        hostile = set(re.findall(r"^def (\w+)", own, re.MULTILINE))
        scored = [t for t in results["tests"] if t["extra_data"]["function"] in hostile]
        assert scored and all(t["score"] == 0 for t in scored)
    else:
        assert results["score"] == 0


def test_raw_escape_attack_as_a_submission(roots, numpy_python):
    """The kernel-level attack script, aimed at the bundle's seed, as the file a student
    uploads: the audit hook stops it first, and it scores and reads nothing."""
    root = roots("a1")
    aim = f"import sys\nsys.argv[1:] = ['1', '1', '/', {str(root / 'source' / 'seed')!r}]\n"
    attack = aim + (REPO / "tests" / "attacks" / "raw_escape.py").read_text()
    results, _ = grade(root, numpy_python, {"a1_rotations.py": attack})
    assert results["score"] == 0
    assert "your file could not be loaded: PermissionError" in results["output"]


def test_notebook_with_any_name(roots, numpy_python):
    import nbformat

    root = roots("a1")
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell("# My rotations"),
                nbformat.v4.new_code_cell(fixture("a1", "reference", root)),
                nbformat.v4.new_code_cell("print(quat_mul([1.0, 0, 0, 0], [0, 1.0, 0, 0]))")]
    results, log = grade(root, numpy_python, {"HW1 (final) v2.ipynb": nbformat.writes(nb)})
    assert results["score"] == sum(t["max_score"] for t in results["tests"]) > 0
    assert "Graded HW1 (final) v2.ipynb" in log


def test_a_folder_of_files_grades_the_one_that_defines_the_functions(roots, numpy_python):
    root = roots("a1")
    metadata = {"id": 424242, "users": [{"email": "ada@example.edu", "id": 7, "name": "Ada"}],
                "assignment": {"title": "Rotations"}}
    results, log = grade(root, numpy_python, {
        "notes.py": "# nothing here\nx = 1\n",
        "helpers/util.py": "def quat_mul(a, b):\n    raise NotImplementedError\n",
        "work/final/mine.py": fixture("a1", "reference", root),
        ".hidden/a1_rotations.py": "def broken(:\n",
    }, metadata=metadata)
    assert results["score"] == sum(t["max_score"] for t in results["tests"])
    said = results["output"].replace("\\", "")
    assert "Graded work/final/mine.py, the one of your 3 files" in said
    assert results["extra_data"]["submission_id"] == 424242
    assert "ada@example.edu" in log


def test_broken_submissions_get_a_results_file_that_says_what_broke(roots, numpy_python):
    root = roots("a1")
    results, _ = grade(root, numpy_python, {})
    assert results["score"] == 0 and results["tests"]  # every test listed, none run
    assert "No .py or .ipynb file was found" in results["output"].replace("\\", "")
    assert all("not run" in t["output"] for t in results["tests"])

    results, _ = grade(root, numpy_python, {"a1_rotations.py": "def quat_mul(a, b):\n"
                                                                "    return (a[0] * \n"})
    assert results["score"] == 0
    assert "line 2: '(' was never closed (Python cannot read" in results["output"]

    results, _ = grade(root, numpy_python, {"a1_rotations.py": b"\xff\xfe not text"})
    assert results["score"] == 0 and "UTF-8" in results["output"]


def test_grader_and_machine_faults_are_not_graded(roots, numpy_python, tmp_path):
    """No results.json and a failing exit: Gradescope shows that the autograder failed, with
    no score in its gradebook, and Regrade grades it again; the log says why."""
    root = roots("a1")
    results = root / "results" / "results.json"
    files = {"a1_rotations.py": fixture("a1", "reference", root)}
    # the grader's Python is missing
    out = run_autograder(root, tmp_path / "no-python", files)
    assert out.returncode != 0 and not results.exists()
    assert "wrote no results.json: not graded" in out.stdout
    # the grader raises: the instructor reads the traceback
    env_file = root / "source" / "bundle.env"
    saved = env_file.read_text()
    env_file.write_text(saved.replace("ASSIGNMENT=a1", "ASSIGNMENT=zz"))
    try:
        out = run_autograder(root, numpy_python, files)
    finally:
        env_file.write_text(saved)
    assert out.returncode != 0 and not results.exists()
    assert "grader fault: not graded, no results.json written" in out.stdout
    assert "Traceback" in out.stdout and "unknown 'zz'" in out.stdout
    if os.geteuid() == 0:  # no user id to lease (nobody's is taken): no sandbox starts
        out = run_autograder(root, numpy_python, files, AUTOGRADER_UIDS="65534-65534")
        assert out.returncode != 0 and not results.exists()
        assert "grader fault: not graded, no results.json written" in out.stdout
        assert ("the sandbox could not be prepared (every user id of range(65534, 65535) is "
                "leased or in use") in out.stdout


def test_the_schema_check_knows_every_documented_key():
    full = {
        "score": 44.0, "execution_time": 136, "output": "x", "output_format": "simple_format",
        "test_output_format": "text", "test_name_format": "text",
        "visibility": "after_due_date", "stdout_visibility": "visible", "extra_data": {},
        "tests": [{"score": 2.0, "max_score": 2.0, "status": "passed", "name": "n",
                   "name_format": "text", "number": "1.1", "output": "o",
                   "output_format": "text", "tags": ["a"], "visibility": "visible",
                   "extra_data": {}}],
        "leaderboard": [{"name": "Accuracy", "value": 0.926},
                        {"name": "Time", "value": 15.1, "order": "asc"},
                        {"name": "Stars", "value": "*****"}],
    }
    assert problems(full) == []
    assert problems({"tests": [{"score": 1}]}) == []  # scores on the tests only
    bad = {"score": True, "visibility": "later", "outptu": "typo", "output_format": "pdf",
           "tests": [{"score": "1", "status": "ok", "tags": [1], "execution_time": 1}, 3],
           "leaderboard": [{"name": "x", "order": "up"}]}
    said = " ".join(problems(bad))
    for expected in ("results.json.score is bool", "visibility is 'later'",
                     "outptu is not a key", "output_format is 'pdf'", "tests[0].score is str",
                     "tests[0].status is 'ok'", "tests[0].tags holds something",
                     "tests[0].execution_time is not a key", "tests[1] is int",
                     "leaderboard[0].order is 'up'", "leaderboard[0] has no value"):
        assert expected in said, expected
    assert problems({"tests": []}) == ["results.json has no top-level score and not every "
                                       "test has one"]
    assert problems([]) == ["results.json holds list, not an object"]


def test_student_text_cannot_become_markdown():
    assert markdown_text("[click](http://x) ![i](y) <b>*") == (
        r"\[click\](http://x) \!\[i\](y) \<b\>\*")
    block = code_block(["a ``` b", "````"])
    fence = block.split("text", 1)[0]
    assert fence == "`" * 5 and block.endswith("\n" + fence)


def test_build_refuses_bad_arguments(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["gradescope", "a1", "--out", str(tmp_path / "x.zip"), "--seed-file",
              str(tmp_path / "missing")])
    assert "--seed-file" in capsys.readouterr().err
    empty = tmp_path / "empty"
    empty.write_text("\n")
    with pytest.raises(SystemExit):
        main(["gradescope", "a1", "--out", str(tmp_path / "x.zip"), "--seed-file", str(empty)])
    with pytest.raises(SystemExit):
        main(["gradescope", "a1", "--out", str(tmp_path / "no" / "such" / "x.zip")])
    assert "--out: cannot write" in capsys.readouterr().err
    # without a seed file a new seed is made, printed once, and is the bundle's
    assert main(["gradescope", "a1", "--out", str(tmp_path / "a1.zip")]) == 0
    printed = capsys.readouterr().err
    seed = printed.rsplit(": ", 1)[1].strip()
    with zipfile.ZipFile(tmp_path / "a1.zip") as z:
        assert z.read("seed").decode().strip() == seed and len(seed) >= 40
    assert stat.S_IMODE((tmp_path / "a1.zip").stat().st_mode) == 0o600
