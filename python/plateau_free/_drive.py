"""The run of :func:`minimize` for the methods with an ask-and-tell form (``'adaptive'``,
``'polished'``, ``'plateau'``): ask, evaluate (:class:`~plateau_free._evaluate._Evaluator`),
tell, then the callback, the history, the progress line and the checkpoint when due. Ctrl-C
ends the run at the next point with its best so far; an exception that ends it carries the
result so far as ``exc.result``."""

from __future__ import annotations

import json
import math
import sys
import time
from typing import Any, Optional

import numpy as np

from . import _native
from ._evaluate import _Evaluator
from ._result import (
    OptimizeResult,
    SearchHistory,
    _adaptive_result,
    _paper_result,
    _stopped_result,
)
from ._saved import _Checkpoint

# Seconds between progress lines (disp=True), and between checkpoints by default: the
# library's.
_DISPLAY_SECONDS = _native.PROGRESS_SECONDS
_CHECKPOINT_SECONDS = _native.CHECKPOINT_SECONDS


class _Progress:
    """What the driver adds to the run's own state: iterations, failures, the adaptive search's
    history rows; saved in the checkpoint with the run."""

    def __init__(self, keep: int) -> None:
        self.nit = 0
        self.nfail = 0
        self.rows: list[list[float]] = []  # (nfev, best value, sigma) per iteration
        self.dropped = 0
        self.keep = keep
        self.started_told = False  # whether the start (the first, lone point) was told
        self.exceptions = 0  # failed evaluations that raised, and the first one's repr
        self.first_error = ""

    def push(self, nfev: int, best: float, sigma: float) -> None:
        """One iteration's row; the oldest beyond the last ``keep`` go once twice as many are
        held (at most ``2 keep`` rows)."""
        self.rows.append([float(nfev), best, sigma])
        if len(self.rows) > 2 * self.keep:
            self.trim()

    def trim(self) -> None:
        cut = len(self.rows) - self.keep
        if cut > 0:
            del self.rows[:cut]
            self.dropped += cut

    def state(self) -> dict[str, Any]:
        return {
            "nit": self.nit,
            "nfail": self.nfail,
            "rows": self.rows,
            "dropped": self.dropped,
            "started_told": self.started_told,
            "exceptions": self.exceptions,
            "first_error": self.first_error,
        }

    def restore(self, saved: dict[str, Any]) -> None:
        self.nit, self.nfail = int(saved["nit"]), int(saved["nfail"])
        self.rows, self.dropped = list(saved["rows"]), int(saved["dropped"])
        self.started_told = bool(saved["started_told"])
        self.exceptions, self.first_error = int(saved["exceptions"]), str(saved["first_error"])

    def history(self) -> SearchHistory:
        self.trim()
        rows = np.array(self.rows, dtype=np.float64).reshape(-1, 3)
        return SearchHistory(
            nfev=rows[:, 0].astype(np.uint64), fun=rows[:, 1], sigma=rows[:, 2], dropped=self.dropped
        )


class _Display:
    """``disp=True``: the library's progress line (``lifecycle::ProgressLine``'s words) on stdout
    every few seconds and at the end, with the failures when there are any."""

    def __init__(self, on: bool, budget: Optional[int]) -> None:
        self.on = on
        self.budget = budget
        self.started = time.monotonic()
        self.last: Optional[float] = None

    def line(self, nit: int, nfev: int, best: float, sigma: float, nfail: int, end: str = "") -> None:
        now = time.monotonic()
        if not self.on or (not end and self.last is not None and now - self.last < _DISPLAY_SECONDS):
            return
        self.last = now
        budget = "" if self.budget is None else f"/{self.budget}"
        failed = f"  failed {nfail}" if nfail else ""
        print(
            f"{'end: ' if end else ''}iteration {nit}  evaluations {nfev}{budget}  best "
            f"{_rust_e(best)}  sigma {_rust_e(sigma)}  elapsed {now - self.started:.1f} s{failed}"
            + (f"  ({end})" if end else ""),
            file=sys.stdout,
            flush=True,
        )


def _rust_e(value: float) -> str:
    """``value`` as Rust's ``{:.3e}`` writes it (``1.234e-5``, ``0.000e0``, ``inf``, ``NaN``)."""
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    mantissa, exponent = f"{value:.3e}".split("e")
    return f"{mantissa}e{int(exponent)}"


class _Driver:
    """One run: the Rust ask-and-tell state ``run``, ``fun`` as :class:`_Evaluator` calls it,
    and what :func:`minimize` asked for around it."""

    def __init__(
        self,
        run: Any,
        evaluate: _Evaluator,
        method: str,
        checked: dict[str, Any],
        budget: int,
        callback: Any,
        checkpoint: Optional[_Checkpoint],
        x0: np.ndarray,
    ) -> None:
        self.run = run
        self.x0 = x0
        self.evaluate = evaluate
        self.method = method
        self.checked = checked
        self.budget = budget
        self.callback = callback
        self.checkpoint = checkpoint
        self.every = checked.get("checkpoint_every")
        self.progress = _Progress(int(checked.get("keep_history", 1_000_000)))
        self.display = _Display(bool(checked.get("disp", False)), budget if method != "plateau" else None)
        self.pending: Optional[tuple[Any, Any]] = None
        self.restored = 0
        self.loaded = False
        self.finished_on_load = False
        self.saved_at = (time.monotonic(), 0)

    def resume(self) -> bool:
        """Reads the checkpoint, if any: returns whether the run was restored from it."""
        if self.checkpoint is None:
            return False
        payload = self.checkpoint.load()
        if payload is None:
            return False
        self.run = _native._AskTell._from_state(json.dumps(payload["state"]))
        self.progress.restore(payload["progress"])
        self.evaluate.failures = self.progress.nfail  # counted over the whole run
        self.evaluate.exceptions = self.progress.exceptions
        pending = payload.get("pending")
        if pending is not None:
            points = np.array(pending["points"], dtype=np.float64)
            self.pending = (points, np.array(pending["seeds"], dtype=np.uint64))
        self.restored = self.progress.nit
        self.loaded = True
        self.finished_on_load = bool(self.run.done)
        return True

    def save(self) -> None:
        if self.checkpoint is None:
            return
        pending = None
        if self.pending is not None:
            pending = {
                "points": self.pending[0].tolist(),
                "seeds": [int(s) for s in self.pending[1]],
            }
        state = json.loads(self.run._state())
        self.checkpoint.save({"state": state, "progress": self.progress.state(), "pending": pending})
        self.saved_at = (time.monotonic(), self.progress.nit)

    def _count_failures(self) -> None:
        """The evaluator's counts into the progress (what a checkpoint keeps)."""
        self.progress.nfail = self.evaluate.failures
        self.progress.exceptions = self.evaluate.exceptions
        if not self.progress.first_error and self.evaluate.first_error is not None:
            self.progress.first_error = repr(self.evaluate.first_error)

    def _due(self) -> bool:
        if self.checkpoint is None or self.every == 0:
            return False
        if self.every is not None:
            return bool(self.progress.nit - self.saved_at[1] >= self.every)
        return time.monotonic() - self.saved_at[0] >= _CHECKPOINT_SECONDS

    def drive(self) -> OptimizeResult:
        """Runs to the end (or the callback's stop, Ctrl-C, an exception) and returns the
        result; saves the checkpoint at the end and on the way out."""
        stop: Optional[str] = None
        try:
            while not self.run.done:
                if self.pending is None:
                    self.pending = self.run.ask()
                    if self.pending is None:
                        break
                points, seeds = self.pending
                flat = np.asarray(points, dtype=np.float64)
                values = self.evaluate(flat, seeds)
                self.run.tell(values.tolist())
                self.pending = None
                self._count_failures()
                stop = self._after_tell()
                if stop is not None:
                    break
                if self._due():
                    self.save()
        except KeyboardInterrupt:
            stop = "interrupted"
        except BaseException as e:
            self._finish_on_error(e)
            raise
        finally:
            self.evaluate.close()
        self.save()
        return self._result(stop)

    def _finish_on_error(self, error: BaseException) -> None:
        """On the way out of an exception: the checkpoint written, the result so far as
        ``error.result``."""
        try:
            self.save()
        finally:
            try:
                setattr(error, "result", self._result("raised", error))
            except Exception:
                pass

    def _after_tell(self) -> Optional[str]:
        """After a tell: the iteration's count, history row, progress line and callback;
        ``'callback'`` when the callback stops the run."""
        if self.method == "plateau":
            step = self.run.last_step()
            if step is None or step[0] <= self.progress.nit:
                return None  # a redraw, or the final evaluation
            self.progress.nit = int(step[0])
        elif not self.progress.started_told:
            self.progress.started_told = True  # the start alone, not an iteration
            return None
        else:
            self.progress.nit += 1
        best = self.run.best()
        nfev = int(self.run.nfev)
        if self.method != "plateau":
            sigma = self.run.sigma()
            self.progress.push(nfev, float("inf") if best is None else best[1], sigma)
        self._show(nfev)
        if self.callback is None:
            return None
        if self.method == "plateau":
            _, x, sigma, value, gradient, at = self.run.last_step()
            stops = self.callback.paper(self.progress.nit - 1, x, sigma, value, gradient, at)
        elif best is None:
            stops = self.callback.adaptive(self.progress.nit, self.x0, float("inf"), nfev)
        else:
            stops = self.callback.adaptive(self.progress.nit, best[0], best[1], nfev)
        return "callback" if stops else None

    def _result(self, stop: Optional[str], error: Optional[BaseException] = None) -> OptimizeResult:
        """The result: the run's own when it ended, else the best so far (the current iterate
        for the paper's loop)."""
        how = None if self.callback is None else self.callback.stop
        if stop is None and self.run.done:
            raw = self.run.result()
            if self.method == "plateau":
                result = _paper_result(raw, raw["final_value"])
            else:
                result = _adaptive_result(raw, self.budget)
        else:
            raw = self._partial()
            final = None
            if stop == "callback" and self.method == "plateau":
                final = self._final_value(raw["x"])
            result = _stopped_result(raw, self.method, stop or "raised", how, error, final)
        return self._finish(result)

    def _partial(self) -> dict[str, Any]:
        """The raw results so far: the paper loop's from the Rust side, the adaptive search's
        best point (the start before any value)."""
        if self.method == "plateau":
            raw: dict[str, Any] = self.run.partial()
            return raw
        best = self.run.best()
        x, fun = (self.x0, float("inf")) if best is None else best
        return {"x": x, "fun": fun, "nit": self.progress.nit, "nfev": int(self.run.nfev)}

    def _final_value(self, x: Any) -> Optional[float]:
        """The paper's loop stopped by its callback: ``fun`` once at the last iterate (with
        the run's seed), as a run that ends by itself."""
        if not self.checked.get("final_evaluation", True):
            return None
        value = self.evaluate(np.asarray(x, dtype=np.float64)[np.newaxis], np.array([self.checked["seed"]], np.uint64))
        return float(value[0])

    def _finish(self, result: OptimizeResult) -> OptimizeResult:
        nfail = self.evaluate.failures
        result.update(nfail=nfail, seed=self.checked["seed"], from_checkpoint=self.loaded)
        if self.method != "plateau":
            result["history"] = self.progress.history()
        self._count_failures()
        if self.progress.first_error:
            result["message"] += (
                f"; fun raised on {self.progress.exceptions} of {result['nfev']} evaluations, "
                f"the first: {self.progress.first_error}"
            )
        if self.loaded and self.checkpoint is not None:
            path = self.checkpoint.path
            if self.finished_on_load:
                result["message"] = f"restored from the finished checkpoint {path}: {result['message']}"
            else:
                result["message"] = (
                    f"continued from the checkpoint {path} at iteration {self.restored}: "
                    f"{result['message']}"
                )
        self._show(int(result["nfev"]), result)
        return result

    def _show(self, nfev: int, result: Optional[OptimizeResult] = None) -> None:
        """The progress line (``disp``): the best value so far (the paper's loop: the last
        iteration's mean value) and the spread; at the end, the result's."""
        if not self.display.on:
            return
        if self.method == "plateau":
            step = self.run.last_step()
            best, sigma = (math.inf, math.nan) if step is None else (step[3], step[2])
        else:
            found = self.run.best()
            best, sigma = (math.inf if found is None else found[1]), self.run.sigma()
        if result is not None:
            best = float(result["fun"])
        end = "" if result is None else str(result["message"])
        self.display.line(self.progress.nit, nfev, best, sigma, self.progress.nfail, end)


def _fresh_error_if_all_failed(result: OptimizeResult, evaluate: _Evaluator) -> None:
    """A run whose every evaluation raised: its first exception, with the result attached."""
    error = evaluate.first_error
    if error is not None and evaluate.exceptions >= int(result["nfev"]) > 0:
        setattr(error, "result", result)
        raise error


def _drive(
    run: Any,
    evaluate: _Evaluator,
    method: str,
    checked: dict[str, Any],
    budget: int,
    callback: Any,
    checkpoint: Optional[_Checkpoint],
    x0: np.ndarray,
) -> OptimizeResult:
    """Runs ``run`` to its end with :class:`_Driver` (resuming from ``checkpoint`` if its file
    exists) and returns the result."""
    driver = _Driver(run, evaluate, method, checked, budget, callback, checkpoint, x0)
    driver.resume()
    result = driver.drive()
    _fresh_error_if_all_failed(result, evaluate)
    return result

