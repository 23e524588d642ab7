"""The package `cdp`: the compiled module `cdp._cdp` re-exported (see python/README.md), and
`cdp.sdf`, signed distance models written like fogleman/sdf (python/cdp/sdf.py).

The functions that take a field also take anything with a `field()` method (a `cdp.sdf.SDF`):
it is called with no arguments first (its box, padded), otherwise they are `cdp._cdp`'s own.
"""
import functools as _functools

from . import _cdp
from ._cdp import *  # noqa: F401,F403  (every public name of the compiled module)

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


for _name in ("polygonize", "marching_cubes", "marching_tetrahedra", "curvature", "project", "trace_creases",
              "corner_normals", "evaluate"):
    globals()[_name] = _accepts_models(getattr(_cdp, _name))

del _name

from . import sdf  # noqa: E402  (after the names above, which sdf does not use)
