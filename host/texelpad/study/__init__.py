"""Study protocols and sessions (docs/lab.md): the papers' protocols as state
machines (pursuit, staircase), the normalised texel space they move in, a
simulated participant, and session files that lose nothing. Pure logic and
files: never imports the link or a web framework (docs/architecture.md)."""
