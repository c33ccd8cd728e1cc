"""texelpad lab's web layer: the one owner of the lab's board (owner.py) and
the ASGI app (server.py, Starlette). The only host package that owns a Board
for the study protocols (docs/architecture.md)."""
