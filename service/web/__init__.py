"""The web page for plant engineers (issue 7), served by the same FastAPI app at ``/``.

``router`` serves the page (plain HTML, one hand-written JS file, one CSS file; no build step and
nothing fetched from elsewhere at run time) and ``POST /ui/plot-data``, the orbit and spectrum
arrays the page draws on ``<canvas>``. See docs/web.md.
"""
from .routes import router

__all__ = ["router"]
