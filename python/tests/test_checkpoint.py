"""``minimize(..., checkpoint=path)``: a run stopped by Ctrl-C (here KeyboardInterrupt raised by
``fun``: the run returns its result so far, status 2) and called again continues from its file
and ends bit for bit as the run left alone; a file of other settings, or a damaged one, is
refused, naming the difference."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import plateau_free


def staircase(x: np.ndarray) -> float:
    """Flat almost everywhere: only the smoothed gradient sees the way down."""
    return float(np.sum((np.round(x) - np.array([1.0, -2.0, 3.0])) ** 2))


class InterruptAt:
    """``staircase`` that raises KeyboardInterrupt at its ``at``-th call, once (never for
    ``at=0``). Every instance is the same objective to a checkpoint (its class's name)."""

    def __init__(self, at: int) -> None:
        self.at = at
        self.calls = 0

    def __call__(self, x: np.ndarray) -> float:
        self.calls += 1
        if self.calls == self.at:
            raise KeyboardInterrupt
        return staircase(x)


OPTIONS: dict[str, Any] = dict(sigma0=1.0, lr=0.05, iterations=60, samples=4, seed=7)


def options_of(method: str) -> dict[str, Any]:
    """OPTIONS that ``method`` takes: SPSA has no samples, finite differences no spread."""
    left_out = {"plateau": (), "spsa": ("samples",), "fd": ("samples", "sigma0")}[method]
    return {k: v for k, v in OPTIONS.items() if k not in left_out}


def iterations_in(path: Path) -> int:
    """The iterations a checkpoint file holds: the driver's (adaptive, polished, plateau) or
    the baselines' loop's."""
    text = path.read_text()
    if "\n" in text:  # the library's file: a header line, then the driven run's state
        state = json.loads(text.split("\n", 1)[1])
        return int(next(iter(state["run"].values()))["run"]["progress"]["iteration"])
    saved = json.loads(text)
    assert len(saved["record"]["sigma"]) == saved["state"]["iteration"]
    return int(saved["state"]["iteration"])


def interrupted(fun: Any, x0: Any, **options: Any) -> Any:
    """A run that ``fun`` interrupts: its result so far, status 2."""
    result = plateau_free.minimize(fun, x0, **options)
    assert result.status == 2 and "interrupted (KeyboardInterrupt)" in result.message, result.message
    return result


def same(a: Any, b: Any) -> None:
    assert a.x.tobytes() == b.x.tobytes()
    assert a.fun == b.fun and a.nit == b.nit and a.nfev == b.nfev
    for name in ("sigma", "fun", "grad_norm", "nfev"):
        assert getattr(a.history, name).tobytes() == getattr(b.history, name).tobytes(), name


@pytest.mark.parametrize("method", ["plateau", "spsa", "fd"])
@pytest.mark.parametrize("every", [None, 0, 7])
def test_interrupted_and_continued_equals_the_run_left_alone(
    tmp_path: Path, method: str, every: int | None
) -> None:
    x0 = np.zeros(3)
    options = options_of(method)
    alone = plateau_free.minimize(InterruptAt(0), x0, method=method, **options)
    assert not alone.from_checkpoint
    path = tmp_path / "run.json"
    interrupted(InterruptAt(37), x0, method=method, checkpoint=path, checkpoint_every=every, **options)
    done = iterations_in(path)
    assert 0 < done < OPTIONS["iterations"], done
    resumed = plateau_free.minimize(
        InterruptAt(0), x0, method=method, checkpoint=path, checkpoint_every=every, **options
    )
    same(alone, resumed)
    assert resumed.from_checkpoint
    assert resumed.message.startswith(f"continued from the checkpoint {path} at iteration {done}: ")
    assert iterations_in(path) == OPTIONS["iterations"]
    # A finished file gives the same result again, without running, and says so.
    calls = InterruptAt(0)
    again = plateau_free.minimize(calls, x0, method=method, checkpoint=path, **options)
    same(alone, again)
    # The final evaluation is in the file.
    assert calls.calls == 0
    assert again.from_checkpoint
    assert again.message.startswith(f"restored from the finished checkpoint {path}: ")
    assert [p.name for p in tmp_path.iterdir()] == ["run.json"]  # no temporary file left


def test_interrupted_twice_still_equals(tmp_path: Path) -> None:
    x0 = np.full(3, 0.4)
    alone = plateau_free.minimize(InterruptAt(0), x0, method="plateau", record_x=True, **OPTIONS)
    path = tmp_path / "run.json"
    for at in (11, 50):
        interrupted(InterruptAt(at), x0, method="plateau", record_x=True, checkpoint=str(path), **OPTIONS)
    resumed = plateau_free.minimize(InterruptAt(0), x0, method="plateau", record_x=True, checkpoint=path, **OPTIONS)
    same(alone, resumed)
    assert alone.history.x.tobytes() == resumed.history.x.tobytes()


@pytest.mark.parametrize(
    "change, named",
    [
        (dict(seed=8), "seed is 7"),
        (dict(lr=0.1), "lr is 0.05"),
        (dict(samples=6), "samples is 4"),
        (dict(iterations=61), "iterations is 60"),
        (dict(sigma0=0.5), r"schedule is .*sigma0=1\.0.* there, .*sigma0=0\.5"),
        (dict(x0=np.ones(3)), r"x0 is \[0\.0,0\.0,0\.0\] there, \[1\.0,1\.0,1\.0\] here"),
        (dict(x0=np.zeros((3, 1))), r"shape is \[3\] there, \[3,1\] here"),
        (dict(bounds=[(-5, 5)] * 3), "bounds is null there"),
        (dict(fun=staircase), r'fun is "test_checkpoint\.InterruptAt" there, "test_checkpoint\.staircase" here'),
        (dict(fun=lambda x: 0.0), r'fun is "test_checkpoint\.InterruptAt" there, "test_checkpoint\..*<lambda>" here'),
    ],
)
def test_other_settings_are_refused_naming_the_difference(
    tmp_path: Path, change: dict[str, Any], named: str
) -> None:
    path = tmp_path / "run.json"
    interrupted(InterruptAt(9), np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    before = path.read_bytes()
    call = {"fun": InterruptAt(0), "x0": np.zeros(3), **OPTIONS, **change}
    with pytest.raises(ValueError, match=named) as info:
        plateau_free.minimize(call.pop("fun"), call.pop("x0"), method="plateau", checkpoint=path, **call)
    assert str(path) in str(info.value)
    assert path.read_bytes() == before  # refused, not overwritten


def test_a_finished_checkpoint_is_not_reused_for_another_fun(tmp_path: Path) -> None:
    # A checkpoint belongs to its objective: a finished run's x must not come back for
    # another fun, silently.
    path = tmp_path / "run.json"
    first = plateau_free.minimize(staircase, np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    assert not first.from_checkpoint and "checkpoint" not in first.message

    def other(x: np.ndarray) -> float:
        return float(np.sum(x**2))

    with pytest.raises(ValueError, match=rf"checkpoint {path} belongs to another run: fun is \"test_checkpoint\.staircase\" there") as info:
        plateau_free.minimize(other, np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    assert "test_checkpoint.test_a_finished_checkpoint_is_not_reused_for_another_fun.<locals>.other" in str(info.value)
    again = plateau_free.minimize(staircase, np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    assert again.from_checkpoint and again.x.tobytes() == first.x.tobytes()
    assert again.message == f"restored from the finished checkpoint {path}: {first.message}"
    assert again.nfev == first.nfev and again.nit == first.nit


@pytest.mark.parametrize(
    "damage",
    [
        lambda b: b[: len(b) // 2],
        lambda b: b"",
        lambda b: b"{}",
        lambda b: b.replace(b'"format":2', b'"format":9'),
        lambda b: b.replace(b'"evaluations":', b'"evaluations":1', 1),
        lambda b: b.replace(b'"iteration":', b'"iteration":1', 1),
    ],
)
def test_damaged_files_are_refused_naming_the_path(tmp_path: Path, damage: Any) -> None:
    path = tmp_path / "run.json"
    interrupted(InterruptAt(9), np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    assert damage(path.read_bytes()) != path.read_bytes()
    path.write_bytes(damage(path.read_bytes()))
    with pytest.raises(ValueError, match="checkpoint") as info:
        plateau_free.minimize(InterruptAt(0), np.zeros(3), method="plateau", checkpoint=path, **OPTIONS)
    assert str(path) in str(info.value)


def test_bad_cadences_are_refused(tmp_path: Path) -> None:
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="checkpoint_every"):
            plateau_free.minimize(
                staircase, np.zeros(3), method="plateau", checkpoint=tmp_path / "b.json", checkpoint_every=bad
            )
    assert os.listdir(tmp_path) == []


def test_a_kept_history_continues_from_the_file(tmp_path: Path) -> None:
    options = {**OPTIONS, "keep_history": 5}
    alone = plateau_free.minimize(InterruptAt(0), np.zeros(3), method="plateau", record_x=True, **options)
    path = tmp_path / "run.json"
    interrupted(InterruptAt(150), np.zeros(3), method="plateau", record_x=True, checkpoint=path, checkpoint_every=1, **options)
    assert iterations_in(path) > 10
    resumed = plateau_free.minimize(InterruptAt(0), np.zeros(3), method="plateau", record_x=True, checkpoint=path, **options)
    same(alone, resumed)
    assert len(resumed.history) == 5 and resumed.history.dropped == OPTIONS["iterations"] - 5
    assert alone.history.x.tobytes() == resumed.history.x.tobytes()


def test_a_path_that_cannot_be_written_fails_before_any_evaluation(tmp_path: Path) -> None:
    calls = []

    def f(x: np.ndarray) -> float:
        calls.append(1)
        return staircase(x)

    path = tmp_path / "no-such-folder" / "run.json"
    with pytest.raises(ValueError, match="run.json"):
        plateau_free.minimize(f, np.zeros(3), budget=300, seed=1, checkpoint=str(path))
    assert calls == []


def test_a_write_that_fails_during_the_run_warns_and_the_run_goes_on(tmp_path: Path) -> None:
    # The checkpoint's folder is removed at evaluation 40 and made again at evaluation 200:
    # the writes due between warn, the run is the run left alone.
    folder = tmp_path / "runs"
    folder.mkdir()
    calls = [0]

    def f(x: np.ndarray) -> float:
        calls[0] += 1
        if calls[0] == 40:
            for p in folder.iterdir():
                p.unlink()
            folder.rmdir()
        if calls[0] == 200:
            folder.mkdir()
        return staircase(x)

    alone = plateau_free.minimize(staircase, np.zeros(3), budget=400, seed=2)
    with pytest.warns(RuntimeWarning, match="not written.*the run goes on"):
        res = plateau_free.minimize(
            f, np.zeros(3), budget=400, seed=2, checkpoint=str(folder / "run.json"),
            checkpoint_every=1,
        )
    assert np.array_equal(res.x, alone.x) and res.fun == alone.fun and res.nfev == alone.nfev
