"""The run of :func:`minimize` for the methods with an ask-and-tell form (``'adaptive'``,
``'polished'``, ``'plateau'``), and of :func:`least_squares`: the library's driver (``_native._drive``: interrupt, progress
line, history, checkpoint) runs it, with ``fun`` evaluated here
(:class:`~plateau_free._evaluate._Evaluator`); this module turns its end into the result.
Ctrl-C ends the run with its best point so far; an exception that ends it carries the result
so far as ``exc.result``."""

from __future__ import annotations

import math
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


class _Run:
    """One run: the Rust ask-and-tell state ``run``, ``fun`` as :class:`_Evaluator` calls it,
    and what :func:`minimize` asked for around it (``settings``: what a checkpoint must
    match, as ``(name, value)`` pairs)."""

    def __init__(
        self,
        run: Any,
        evaluate: _Evaluator,
        method: str,
        checked: dict[str, Any],
        budget: int,
        callback: Any,
        settings: Optional[list[tuple[str, str]]],
        x0: np.ndarray,
    ) -> None:
        self.run = run
        self.x0 = x0
        self.evaluate = evaluate
        self.method = method
        # The paper's loop and its baselines: the last iterate, the paper's history.
        self.paper = method in ("plateau", "fd", "spsa")
        self.checked = checked
        self.budget = budget
        self.callback = callback
        self.settings = settings

    def drive(self) -> OptimizeResult:
        """Runs to the end (or the callback's stop, Ctrl-C, an exception) and returns the
        result; an exception leaves with the result so far as ``exc.result``."""
        path = self.checked.get("checkpoint")
        try:
            ended = _native._drive(
                self.run,
                self.evaluate,
                disp=bool(self.checked.get("disp", False)),
                keep=int(self.checked.get("keep_history", 1_000_000)),
                checkpoint=path,
                checkpoint_every=self.checked.get("checkpoint_every"),
                settings=self.settings or [],
                after=None if self.callback is None else self._after,
            )
        except KeyboardInterrupt:
            ended = {"why": "interrupted", "restored": None, "rows": [], "dropped": 0}
        except BaseException as e:
            try:
                setattr(e, "result", self._result({"why": "raised", "restored": None, "rows": [], "dropped": 0}, e))
            except Exception:
                pass
            raise
        finally:
            self.evaluate.close()
        return self._result(ended)

    def _after(self, nit: int, nfev: int, info: Any) -> Any:
        """The callback after an iteration, in the method's form."""
        if self.paper:
            _, x, sigma, value, gradient, at = info
            return self.callback.paper(nit - 1, x, sigma, value, gradient, at)
        if info is None:
            return self.callback.adaptive(nit, self.x0, math.inf, nfev)
        return self.callback.adaptive(nit, info[0], info[1], nfev)

    def _result(self, ended: dict[str, Any], error: Optional[BaseException] = None) -> OptimizeResult:
        """The result: the run's own when it ended, else the best so far (the current iterate
        for the paper's loop)."""
        stop = ended["why"]
        how = None if self.callback is None else self.callback.stop
        if stop is None and self.run.done:
            raw = self.run.result()
            if self.paper:
                result = _paper_result(raw, raw["final_value"])
            else:
                result = _adaptive_result(raw, self.budget)
        else:
            raw = self._partial()
            final = None
            if stop == "callback" and self.paper:
                final = self._final_value(raw["x"])
            method = "plateau" if self.paper else self.method
            result = _stopped_result(raw, method, stop or "raised", how, error, final)
        return self._finish(result, ended)

    def _partial(self) -> dict[str, Any]:
        """The raw results so far: the paper loop's from the Rust side, the adaptive search's
        best point (the start before any value)."""
        if self.paper:
            raw: dict[str, Any] = self.run.partial()
            return raw
        best = self.run.best()
        x, fun = (self.x0, math.inf) if best is None else best
        return {"x": x, "fun": fun, "nit": int(self.run.nit), "nfev": int(self.run.nfev)}

    def _final_value(self, x: Any) -> Optional[float]:
        """The paper's loop stopped by its callback: ``fun`` once at the last iterate (with
        the run's seed), as a run that ends by itself."""
        if not self.checked.get("final_evaluation", True):
            return None
        value = self.evaluate(np.asarray(x, dtype=np.float64)[np.newaxis], np.array([self.checked["seed"]], np.uint64))
        return float(value[0])

    def _finish(self, result: OptimizeResult, ended: dict[str, Any]) -> OptimizeResult:
        e = self.evaluate
        result.update(nfail=e.failures, seed=self.checked["seed"], from_checkpoint=ended["restored"] is not None)
        if not self.paper:
            rows = np.array(ended["rows"], dtype=np.float64).reshape(-1, 3)
            result["history"] = SearchHistory(
                nfev=rows[:, 0].astype(np.uint64), fun=rows[:, 1], sigma=rows[:, 2], dropped=int(ended["dropped"])
            )
        if e.first_error_text:
            result["message"] += (
                f"; fun raised on {e.exceptions} of {result['nfev']} evaluations, the first: {e.first_error_text}"
            )
        if ended["restored"] is not None:
            path = self.checked["checkpoint"]
            at, finished = ended["restored"]
            if finished:
                result["message"] = f"restored from the finished checkpoint {path}: {result['message']}"
            else:
                result["message"] = f"continued from the checkpoint {path} at iteration {at}: {result['message']}"
        return result


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
    settings: Optional[list[tuple[str, str]]],
    x0: np.ndarray,
) -> OptimizeResult:
    """Runs ``run`` to its end on the library's driver (resuming from the checkpoint, if its
    file exists) and returns the result."""
    result = _Run(run, evaluate, method, checked, budget, callback, settings, x0).drive()
    _fresh_error_if_all_failed(result, evaluate)
    return result
