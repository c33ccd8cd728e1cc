"""Preference-driven texture search (seed 003): CMA-ES (the `cma` library)
driven by a participant's choices. Pure logic: no link, no web framework."""
