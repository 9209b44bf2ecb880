"""Exceptions of liemid."""

from __future__ import annotations


class ConvergenceError(RuntimeError):
    """A step failed numerically: Newton's method for the midpoint equation did not
    converge, the step would turn the body by more than half a turn, or the state became
    non-finite. The step is too large for the rotation rate: reduce it.

    Attributes
    ----------
    t : float
        Time at the start of the failing step (s).
    h : float
        The step that failed (s).
    """

    def __init__(self, message: str, t: float, h: float) -> None:
        super().__init__(message)
        self.t = t
        self.h = h

    def __reduce__(self) -> tuple[type, tuple[str, float, float]]:
        return (type(self), (str(self), self.t, self.h))
