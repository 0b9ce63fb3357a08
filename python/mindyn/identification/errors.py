"""Errors of the identification: the data cannot give what was asked."""

from __future__ import annotations

from .._core import Error


class IdentificationError(Error, ValueError):
    """The data cannot identify the requested parameters."""


class RankDeficientError(IdentificationError):
    """The stacked regressor is rank deficient; ``unidentifiable`` names the base parameters that
    the data cannot separate from the others."""

    def __init__(self, message: str, unidentifiable: list[str], rank: int):
        super().__init__(message)
        self.unidentifiable = unidentifiable
        self.rank = rank
