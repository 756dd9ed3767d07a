"""What a6's rollout tests cost a submission: the step functions called ~2,000 times.

Run:  .venv/bin/python benchmarks/rollout_pace.py [--repeats 3] [--slow-ms 0] [FILE ...]

For each submission (by default the numpy reference fixture and the plain-Python-loop one,
``tests/fixtures/a6/{reference,plain_loops}.py``; ``--slow-ms N`` adds a copy of the loop one
that busy-waits N ms in every call) and each rollout test, wall-clock figures, the best of
``--repeats`` (the machine may be shared):

- the function alone: ms per call in this process, over the test's own runs (the state
  carried as the grader carries it);
- through the sandbox: ms per step as the grader's pace measures it (the call, its
  round trip to the child, validating the answer and advancing the state), and the ms per
  step that would fit the test's own ``Rollout.seconds``; their ratio is the headroom;
- the score, each test's verdict, and the whole check's wall time against its bound
  (``Limits.budget`` plus every rollout test's own seconds: docs/sandbox.md).
"""

from __future__ import annotations

import argparse
import importlib.util
import tempfile
import time
from pathlib import Path
from types import ModuleType

from autograder import check
from autograder.assignments import load
from autograder.limits import DEFAULT_LIMITS
from autograder.spec import Test, case_rng

REPO = Path(__file__).resolve().parents[1]
FIXTURES = REPO / "tests" / "fixtures" / "a6"
SEED = "benchmark-seed"
SLOW = '''

import time as _time

_fast = {f.__name__: f for f in (rigid_body_step, pd_torque, balance_torque)}


def _slowed(name):
    def call(*args):
        end = _time.perf_counter() + {seconds!r}
        while _time.perf_counter() < end:
            pass
        return _fast[name](*args)
    return call


rigid_body_step = _slowed("rigid_body_step")
pd_torque = _slowed("pd_torque")
balance_torque = _slowed("balance_torque")
'''


def module(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"submission_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def alone(test: Test, mod: ModuleType) -> float:
    """ms per call of the submission's function alone, over the test's runs."""
    rollout = test.rollout
    assert rollout is not None
    fn = getattr(mod, test.function)
    spent, calls = 0.0, 0
    for case in test.cases(case_rng(test, None)):
        state = rollout.start(case.args)
        for _ in range(rollout.steps):
            args = rollout.call(state)
            t = time.perf_counter()
            answer = fn(*args)
            spent += time.perf_counter() - t
            calls += 1
            state = rollout.advance(state, answer)
    return 1e3 * spent / calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--slow-ms", type=float, default=0.0)
    args = parser.parse_args()
    a6 = load("a6")
    rollouts = [t for t in a6.tests if t.rollout is not None]
    bound = DEFAULT_LIMITS.budget + sum(t.rollout.seconds for t in rollouts if t.rollout)
    with tempfile.TemporaryDirectory() as tmp:
        files = args.files or [FIXTURES / "reference.py", FIXTURES / "plain_loops.py"]
        if args.slow_ms:
            slow = Path(tmp) / f"plain_loops_{args.slow_ms:g}ms.py"
            slow.write_text((FIXTURES / "plain_loops.py").read_text()
                            + SLOW.format(seconds=args.slow_ms / 1e3))
            files.append(slow)
        for path in files:
            mod = module(path)
            print(f"\n{path.name}")
            own = {t.name: min(alone(t, mod) for _ in range(args.repeats)) for t in rollouts}
            best: dict[str, float] = {}
            for _ in range(args.repeats):
                result = check("a6", path, seed=SEED)
                for tr in result.tests:
                    if tr.test.rollout is not None:
                        best[tr.test.name] = min(best.get(tr.test.name, 1e9), tr.elapsed)
            for t in rollouts:
                assert t.rollout is not None
                tr = next(r for r in result.tests if r.test.name == t.name)
                calls = t.rollout.steps * len(tr.cases)
                step = 1e3 * best[t.name] / calls
                fits = 1e3 * t.rollout.seconds / calls
                kinds = ", ".join(c.kind for c in tr.cases)
                print(f"  {t.name}: runs {kinds}\n    {own[t.name]:.3f} ms a call alone; ",
                      end="")
                cut = next((c for c in tr.cases if c.kind == "skipped"), None)
                if cut is not None:  # the calls made are fewer: the report says how many
                    print(f"out of time ({best[t.name]:.1f} s): {cut.reason}")
                    continue
                print(f"{calls} calls, {step:.2f} ms a step through the sandbox (the test "
                      f"{best[t.name]:.1f} s of its {t.rollout.seconds:g} s); {fits:.1f} ms "
                      f"would fit: headroom {fits / step:.0f}x")
            print(f"  score {result.score:g} / {result.max_score:g}, checked in "
                  f"{result.elapsed:.1f} s (bound {bound:g} s: {DEFAULT_LIMITS.budget:g} s + "
                  f"the rollout tests' own {bound - DEFAULT_LIMITS.budget:g} s)")


if __name__ == "__main__":
    main()
