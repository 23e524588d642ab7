"""The adaptive method's blocks meshed on a Dask cluster: `cdp.polygonize(field, client=CLIENT)`.

The run lays the blocks out on the client (the seed grid, the cut planes, the seams), hands each
block's task to the cluster as a Dask task, assembles the pieces in block order and goes on on the
client (what no block holds, the band around the seams, the checks), as with blocks run on the
client's own threads (AdaptiveOptions::block_runner, cdp/core/block_tasks.h). The mesh is the same
bit for bit on any number of workers and in any order the tasks run; a worker lost in the middle of
a run costs only its tasks, which Dask runs again elsewhere.

The field travels as its recipe, the call of the cdp factory that made it (cdp.field_from_json and
its JSON or file, the model functions and their keywords, cdp.expression and the cdp.sdf models,
cdp.callable_field and its Python functions, cdp.volume_field and its array), sent once as a task
whose result the workers share (made again if every worker holding it is lost) and built once per
worker thread. Files a field reads (VIS and MPU points, a
volume's file) are read by the workers from the same absolute path: on a cluster of several
machines, a shared file system. The workers run the same build of cdp as the client (the tasks are
this build's bytes, and are refused otherwise).

Imported only when a client is given: the single-machine path needs no Dask.
"""
import functools
import hashlib
import itertools
import threading
import uuid

import distributed

from . import _cdp

__all__ = ["polygonize", "block_runner"]


class _Recipe:
    """A field's recipe as one opaque object (Dask reads a tuple in a task's arguments as a task
    when its first element is callable: a callable_field's recipe), building the field once per
    thread of the worker that holds it: fields made from Python functions are not safe to call
    from two threads at once, and tasks of one worker run on its threads."""

    def __init__(self, recipe):
        self.recipe = recipe
        self._local = threading.local()

    def __getstate__(self):
        return {"recipe": self.recipe}

    def __setstate__(self, state):
        self.recipe = state["recipe"]
        self._local = threading.local()

    def field(self):
        field = getattr(self._local, "field", None)
        if field is None:
            name, args, kwargs = self.recipe
            field = self._local.field = getattr(_cdp, name)(*args, **kwargs)
        return field


def _same(recipe):
    """The recipe's task: its result is the recipe, held by a worker and made again if lost."""
    return recipe


def _mesh_block(task, recipe, level, build):
    """A Dask task: one block's piece, from its task's bytes, on the field built from its recipe,
    by the same build of cdp as the client's."""
    if _build() != build:
        raise RuntimeError(f"cdp.polygonize(client=...): the worker's cdp ({_cdp.__file__}) is another build than the "
                           "client's; run the same build on every worker")
    return _cdp._run_block_task(recipe.field(), task, level)


@functools.lru_cache(maxsize=None)
def _build():
    """The compiled module's identity: a hash of its file (a task is this build's bytes)."""
    with open(_cdp.__file__, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


# How often a run waiting on its tasks looks whether it was cancelled (cancel, Ctrl-C), seconds.
POLL_SECONDS = 0.2


def block_runner(client, field, level=0.0):
    """The block runner (cdp._cdp.polygonize's block_runner) that meshes a run's blocks on `client`'s
    workers: the field's recipe sent once (a task whose result the workers share), then one task a block, submitted
    largest first with priorities in that order (Dask runs higher priorities first), gathered in
    the run's order. An error of a task (a field its worker cannot build: a missing points file)
    is raised here as the task raised it; a worker lost in the middle costs only its tasks, which
    the scheduler gives to another. Cancelling the run (its token, Ctrl-C) cancels the tasks left
    and raises cdp.CancelledError within POLL_SECONDS."""
    from . import _recipe

    run = f"cdp-block-{uuid.uuid4().hex}"
    # The recipe as a task of its own, not scattered data: data scattered to workers that all die
    # is lost for good (the tasks that need it are cancelled), a task's result is made again.
    recipe = client.submit(_same, _Recipe(_recipe(field, "cdp.polygonize(client=...)")), key=f"{run}-recipe",
                           pure=False)
    calls = itertools.count()

    def run_blocks(tasks, cancelled=lambda: False):
        # Each call (a run that meshes again lays out again) under keys of its own.
        prefix = f"{run}-{next(calls)}"
        futures = [client.submit(_mesh_block, task, recipe, level, _build(), key=f"{prefix}-{i}",
                                 priority=len(tasks) - i, pure=False)
                   for i, task in enumerate(tasks)]
        try:
            while True:
                if cancelled():
                    raise _cdp.CancelledError("adaptive: cancelled while the cluster meshed the blocks")
                try:
                    distributed.wait(futures, timeout=POLL_SECONDS)
                    break
                except (TimeoutError, distributed.TimeoutError):
                    if any(f.status == "error" for f in futures):
                        break  # gather raises the first task's error
            return client.gather(futures)
        finally:
            client.cancel(futures)

    return run_blocks


def polygonize(field, method="adaptive", *, client, **options):
    """cdp.polygonize with the blocks meshed as tasks on `client` (a dask.distributed.Client):
    method "adaptive" with blocks (blocks=True is implied). Returns what cdp.polygonize returns,
    the same mesh bit for bit as the one-process run with blocks=True; stats["blocks"]
    ["task_bytes"] and ["piece_bytes"] say what was sent and received."""
    from . import Mesh

    if method != "adaptive":
        raise ValueError(f'cdp.polygonize(client=...): the blocks are the adaptive method\'s, not "{method}"\'s')
    if options.get("blocks") is False:
        raise ValueError("cdp.polygonize(client=...) meshes blocks: blocks=False asks for tracking alone")
    if options.get("block_runner") is not None:
        raise ValueError("cdp.polygonize: give client or block_runner, not both")
    options["blocks"] = True
    level = options.get("level") or 0.0
    runner = block_runner(client, field, float(level))
    options["block_runner"] = runner
    return Mesh(*_cdp.polygonize(field, method, **options))
