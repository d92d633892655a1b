"""Starting gmsh without losing the process's signal handlers.

``gmsh.initialize`` installs its own handlers for SIGTERM (and others) at the C level and does
not restore them, so that afterwards a SIGTERM ends the process at once, past the command line's
handler, which lets a run say it was stopped and release what it holds (docs/method.md §14).
:func:`initialize` puts Python's handlers back.
"""

from __future__ import annotations

import signal

#: Signals whose Python handler is put back after gmsh starts.
KEPT = (signal.SIGINT, signal.SIGTERM)


def initialize() -> None:
    """``gmsh.initialize(interruptible=False)``, then the Python handlers of :data:`KEPT` again
    (where this thread may set them: the main thread)."""
    import gmsh

    handlers = {sig: signal.getsignal(sig) for sig in KEPT}
    gmsh.initialize(interruptible=False)
    for sig, handler in handlers.items():
        if handler is None:  # set outside Python: nothing to put back
            continue
        try:
            signal.signal(sig, handler)
        except ValueError:  # not the main thread
            return
