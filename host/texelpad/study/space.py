"""The normalised texel space the study's protocols move in: texelpad.space,
under the name the study's modules import it by (`from .space import Point`).
It lives below the study and the preference search (texelpad.search, which
the study's protocols drive), so the search needs nothing of the study
(docs/architecture.md)."""
from __future__ import annotations

from ..space import (ABOVE_NYQUIST, IRREG_DB_AT_0, IRREG_DB_PER_V, PITCH_DB_AT_0,
                     PITCH_DB_PER_U, Point, aliased_samples, check_above_nyquist,
                     irregularity_db, is_above_nyquist, pitch_db, texel_params, to_point)

__all__ = ["ABOVE_NYQUIST", "IRREG_DB_AT_0", "IRREG_DB_PER_V", "PITCH_DB_AT_0",
           "PITCH_DB_PER_U", "Point", "aliased_samples", "check_above_nyquist",
           "irregularity_db", "is_above_nyquist", "pitch_db", "texel_params", "to_point"]
