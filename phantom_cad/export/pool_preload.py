"""What the build's fork server imports when it starts (``workers.mp_context``, the start method
once this process has loaded OCP): build123d, as the workers load it
(``cad.kernel.import_build123d``: without scikit-learn), and the workers' module, so that each
worker forked from the server starts with them instead of importing them. Nothing of OpenCascade
runs here: the server starts no thread pool a forked child could deadlock on.

The server exits with the process that started it (``workers.die_with_parent``): its workers hold
the server's liveness pipe open, so it would otherwise outlive a killed build, and they with it
(they watch the server, ``workers.watched_parent``)."""

from ..cad import kernel
from ..workers import die_with_parent
from . import pool  # noqa: F401  (loaded for the workers)

die_with_parent(None)
kernel.import_build123d()
