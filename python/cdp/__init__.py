"""The package `cdp`: the compiled module `cdp._cdp` re-exported (see python/README.md), and
`cdp.sdf`, signed distance models written like fogleman/sdf (python/cdp/sdf.py), and `cdp.trace`,
numpy functions of points turned into expression fields (python/cdp/trace.py).

The functions that take a field also take anything with a `field()` method (a `cdp.sdf.SDF`):
it is called with no arguments first (its box, padded), otherwise they are `cdp._cdp`'s own.
"""
import functools as _functools
import typing as _typing
import warnings as _warnings
import os as _os

from . import _cdp

# Fields that travel to other processes (a cluster's workers, cdp.distributed; pickle): every
# field a factory of the compiled module makes keeps the call that made it, its recipe, with file
# names made absolute, so that a worker builds the same field from its JSON description, its
# keywords, or its Python callable and arrays (pickled). Patched in the compiled module itself, so
# that cdp.sdf and cdp.trace, which call it, make fields that travel too.
_FIELD_FACTORIES = ("field_from_json", "sphere", "ellipsoid", "torus", "blobs", "expression", "callable_field",
                    "volume_field")


def _portable(name, args, kwargs):
    """The factory's arguments as another process (another working directory) reads them."""
    if name != "field_from_json":
        return args, kwargs
    bound = dict(zip(("spec", "base_dir"), args), **kwargs)
    spec, base_dir = bound.get("spec"), bound.get("base_dir")
    if isinstance(spec, (str, bytes, _os.PathLike)):
        return (_os.path.abspath(spec),), {}
    return (spec, _os.path.abspath(base_dir if base_dir is not None else _os.getcwd())), {}


def _freeze(value, arrays):
    """value as the factory read it, so that a caller's later changes cannot make the workers build
    another field: dicts, lists and tuples copied; a numpy array kept (a copy could double a large
    volume's memory) with a checksum of its bytes in `arrays`, checked when the recipe is sent."""
    if isinstance(value, dict):
        return {k: _freeze(v, arrays) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_freeze(v, arrays) for v in value)
    if type(value).__module__ == "numpy" and hasattr(value, "tobytes"):
        arrays.append((value, _checksum(value)))
    return value


def _checksum(array):
    import zlib
    import numpy
    return zlib.crc32(memoryview(numpy.ascontiguousarray(array)).cast("B"))


def _keeps_recipe(name, factory):
    @_functools.wraps(factory)
    def wrapper(*args, **kwargs):
        field = factory(*args, **kwargs)
        arrays = []
        args, kwargs = _portable(name, args, kwargs)
        field._cdp_recipe = (name, _freeze(args, arrays), _freeze(kwargs, arrays))
        field._cdp_recipe_arrays = arrays
        return field

    return wrapper


def _build_field(name, args, kwargs):
    """A field from its recipe (Field.__reduce__, cdp.distributed)."""
    return getattr(_cdp, name)(*args, **kwargs)


def _recipe(field, doing):
    """The field's recipe for `doing` (pickling, a cluster), checked: a TypeError for a field no
    factory made, a ValueError for one whose array was changed since."""
    recipe = getattr(field, "_cdp_recipe", None)
    if recipe is None:
        raise TypeError(f"{doing}: the field ({field.type}) was not made by a cdp factory (field_from_json, a model "
                        "function, expression, callable_field, volume_field, a cdp.sdf model)")
    for array, checksum in getattr(field, "_cdp_recipe_arrays", ()):
        if _checksum(array) != checksum:
            raise ValueError(f"{doing}: an array the field was made from was changed since (cdp.{recipe[0]}): "
                             "another process would build another field; make the field again")
    return recipe


def _field_reduce(field):
    return _build_field, _recipe(field, "pickling a cdp.Field")


for _name in _FIELD_FACTORIES:
    setattr(_cdp, _name, _keeps_recipe(_name, getattr(_cdp, _name)))
_cdp.Field.__reduce__ = _field_reduce

from ._cdp import *  # noqa: E402,F401,F403  (every public name of the compiled module)
from ._version import __version__  # noqa: F401  (written by python/CMakeLists.txt from the project's version)

__doc__ = _cdp.__doc__
__all__ = [name for name in dir(_cdp) if not name.startswith("_")]

def _accepts_models(function):
    """function(field, ...) that also takes an object with a field() method (cdp.sdf.SDF)."""

    @_functools.wraps(function)
    def wrapper(field, *args, **kwargs):
        if not isinstance(field, _cdp.Field) and callable(getattr(field, "field", None)):
            field = field.field()
        return function(field, *args, **kwargs)

    wrapper.__module__ = __name__
    return wrapper


class Mesh(_typing.NamedTuple):
    """What polygonize, marching_cubes and marching_tetrahedra return: a named tuple, so both
    mesh.vertices and V, F, N, stats = mesh work.

    vertices: (N, 3) float64. faces: (M, 3) int32, counter-clockwise seen from outside.
    normals: (N, 3) float64 unit normals (the field's gradient, normalised), or None where the
    method has none. stats: the run's statistics (build/bin/polygonize's STATS.json as a dict);
    stats["summary"], the figures to read first: watertight, closed, manifold, oriented, outward, components, genus,
    smallest_angle_degrees, degenerate_triangles."""

    vertices: _typing.Any
    faces: _typing.Any
    normals: _typing.Any
    stats: dict


def _returns_mesh(function):
    """function(...) -> (V, F, N, stats) as a Mesh; return_normals, which once chose between a
    3-tuple and a 4-tuple, is accepted with a DeprecationWarning and changes nothing."""

    @_functools.wraps(function)
    def wrapper(*args, return_normals=None, **kwargs):
        if return_normals is not None:
            _warnings.warn("return_normals is deprecated: the result is a cdp.Mesh whose normals are always there "
                           "(V, F, N, stats = ...)", DeprecationWarning, stacklevel=2)
        return Mesh(*function(*args, **kwargs))

    wrapper.__module__ = __name__
    return wrapper


def _distributes(function):
    """polygonize(field, ..., client=None): with a dask.distributed.Client, the blocks meshed on its
    workers (cdp.distributed), imported only then: the single-machine path needs no Dask."""

    @_functools.wraps(function)
    def wrapper(field, *args, client=None, **kwargs):
        if client is None:
            return function(field, *args, **kwargs)
        from . import distributed
        return distributed.polygonize(field, *args, client=client, **kwargs)

    wrapper.__module__ = __name__
    return wrapper


for _name in ("polygonize", "marching_cubes", "marching_tetrahedra"):
    globals()[_name] = _returns_mesh(_accepts_models(getattr(_cdp, _name)))
def _names_why_not_traced(function):
    """polygonize(field, ...) whose error at a black box's crease also says why cdp.trace could
    not follow the function (CallableField.trace_error, set by callable_field), so that the
    caller knows what to write differently."""

    @_functools.wraps(function)
    def wrapper(field, *args, **kwargs):
        try:
            return function(field, *args, **kwargs)
        except _cdp.LimitExceededError as e:
            why = getattr(field, "trace_error", None)
            if not why or "cdp.trace can follow" not in str(e):
                raise
            raise _cdp.LimitExceededError(f"{e}; cdp.trace could not follow this function: {why}") from None

    wrapper.__module__ = __name__
    return wrapper


class ToleranceWarning(UserWarning):
    """polygonize's mesh has triangles farther from the surface than the tolerance asked for
    (stats["quality"]["over_tolerance"]): detail the refinement could not split further. The mesh
    is closed and valid and the rest of it keeps the bound; build/bin/polygonize warns alike."""


class CreaseWarning(UserWarning):
    """polygonize was asked to follow the field's creases (creases="follow", the default) and
    could not (stats["creases"]["fallback"] says why): the surface is meshed across them as smooth,
    its sharp edges cut by chords. The mesh is closed and valid; build/bin/polygonize warns alike."""


def _warns_where_the_mesh_falls_short(function):
    """polygonize(...) that warns where its mesh breaks a promise the program names on stderr,
    which a caller reading only the mesh would not see: triangles beyond the tolerance
    (ToleranceWarning), creases asked for and not followed (CreaseWarning)."""

    @_functools.wraps(function)
    def wrapper(*args, **kwargs):
        mesh = function(*args, **kwargs)
        stats = mesh.stats
        quality = stats.get("quality", {})
        if stats.get("sizing") == "tolerance" and quality.get("over_tolerance", 0) > 0:
            _warnings.warn("{} triangles lie farther from the surface than the tolerance {:g} (up to {:g}, near "
                           "({:g}, {:g}, {:g})); the refinement could not split them further (edges too short to "
                           "halve, or splits that would fold)".format(
                               quality["over_tolerance"], stats["tolerance"], quality["over_tolerance_worst"],
                               quality["over_tolerance_near_x"], quality["over_tolerance_near_y"],
                               quality["over_tolerance_near_z"]), ToleranceWarning, stacklevel=2)
        creases = stats.get("creases", {})
        if creases.get("handling") == "follow" and not creases.get("followed") and creases.get("fallback"):
            _warnings.warn("the creases are not followed, the surface is meshed across them as smooth ({})".format(
                creases["fallback"]), CreaseWarning, stacklevel=2)
        return mesh

    wrapper.__module__ = __name__
    return wrapper


polygonize = _warns_where_the_mesh_falls_short(  # noqa: F811
    _returns_mesh(_accepts_models(_names_why_not_traced(_distributes(_cdp.polygonize)))))
# Its signature line (the compiled function's, which the stubs' test reads) with `client` too.
_first, _rest = (_cdp.polygonize.__doc__ or "\n").split("\n", 1)
polygonize.__doc__ = _first.replace("block_runner: object = None", "block_runner: object = None, client: object = None",
                                    1) + "\n" + _rest
del _first, _rest
for _name in ("curvature", "project", "trace_creases", "corner_normals", "crease_angles", "evaluate"):
    globals()[_name] = _accepts_models(getattr(_cdp, _name))

del _name
__all__ += ["Mesh", "ToleranceWarning", "CreaseWarning"]

from . import sdf  # noqa: E402  (after the names above, which sdf does not use)
from .trace import TraceError, trace, trace_formula  # noqa: E402

_trace = trace  # callable_field's keyword `trace` hides the function's name there

__all__ += ["TraceError", "trace", "trace_formula"]


@_functools.wraps(_cdp.callable_field)
def callable_field(f, bounds, gradient=None, hessian=None, *, trace=True, **kwargs):
    black_box = _cdp.callable_field(f, bounds, gradient, hessian, **kwargs)  # checks every argument
    black_box.trace_error = None  # not traced: trace=False, or derivatives given
    if trace and gradient is None and hessian is None:
        try:
            return _trace(f, bounds)
        except TraceError as e:
            # A black box after all: derivatives by central differences, creases unknown. Why,
            # for polygonize's error where the mesh meets a crease (_names_why_not_traced).
            black_box.trace_error = str(e)
    return black_box


callable_field.__module__ = __name__
callable_field.__doc__ = (
    "callable_field(f, bounds, gradient=None, hessian=None, *, trace=True, lipschitz=None, gradient_step=None, "
    "hessian_step=None, smooth=False)\n\n"
    "A field from a Python function of points. With trace=True (the default) and no gradient or hessian given, f "
    "is first traced (cdp.trace: called once on symbols; a function made of numpy arithmetic becomes an "
    "expression field with exact derivatives and known creases, and no Python runs while meshing); if it cannot "
    "be (cdp.trace(f, bounds) raises TraceError saying why; the black box keeps the reason as its trace_error, "
    "which polygonize's error at a crease of it quotes), or with trace=False, it is the black box below, "
    "called on every batch of points.\n\n" + (_cdp.callable_field.__doc__ or ""))
