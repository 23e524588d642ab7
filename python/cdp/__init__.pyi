# Type stubs of the package cdp (python/cdp/__init__.py): the compiled module's names (_cdp.pyi),
# the functions that also take a model with a field() method (a cdp.sdf.SDF), and the names
# defined in Python. tests/python/test_stubs.py checks them against the package.
from typing import Any, Callable, Literal, NamedTuple, Protocol, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import sdf as sdf
from ._cdp import *
from ._cdp import CallableField, CancelToken, Field
from .trace import TraceError as TraceError, trace as trace, trace_formula as trace_formula

__version__: str

class _HasField(Protocol):
    def field(self) -> Field: ...

# A Field, or a model whose field() (its box, padded) gives one.
_FieldLike = Field | _HasField
_Bounds = ArrayLike

class ToleranceWarning(UserWarning): ...
class CreaseWarning(UserWarning): ...

class Mesh(NamedTuple):
    vertices: NDArray[np.float64]
    faces: NDArray[np.int32]
    normals: NDArray[np.float64] | None
    stats: dict[str, Any]

def callable_field(f: Callable[[NDArray[np.float64]], ArrayLike], bounds: _Bounds,
                   gradient: Callable[[NDArray[np.float64]], ArrayLike] | None = None,
                   hessian: Callable[[NDArray[np.float64]], ArrayLike] | None = None, *, trace: bool = True,
                   lipschitz: float | None = None, gradient_step: float | None = None,
                   hessian_step: float | None = None, smooth: bool = False) -> Field: ...

# _cdp's functions, taking a model in place of a Field too (the same parameters otherwise). The
# meshing functions return a Mesh and still take the deprecated return_normals (Mesh.normals is
# always there).

def polygonize(field: _FieldLike, method: Literal["adaptive", "mc", "mt"] = "adaptive", *,
               return_normals: bool = False, progress: Callable[[float], object] | None = None,
               phase: Callable[[str], object] | None = None, cancel: CancelToken | None = None,
               block_runner: Callable[[list[bytes], Callable[[], bool]], Sequence[bytes]] | None = None, client: Any = None,
               level: float = 0.0,
               factor: float | None = None, tolerance: float | None = None, chord: float | None = None,
               min_edge: float | None = None, max_edge: float | None = None,
               triangle_count: Literal["hartmann", "paper_floor"] | None = None,
               variant: Literal["improved", "paper"] | None = None,
               creases: Literal["follow", "ignore"] | None = None,
               curvature: bool | None = None, blocks: bool | None = None,
               check_self_intersections: bool | None = None,
               cell: float | None = None, precision: int | None = None,
               traversal: Literal["continuation", "grid"] | None = None,
               face_ambiguity: Literal["asymptotic_decider", "join_inside", "separate_inside"] | None = None,
               seed_resolution: int | None = None, max_triangles: int | None = None,
               threads: int | None = None) -> Mesh: ...
def marching_cubes(field: _FieldLike, *, return_normals: bool = False,
                   progress: Callable[[float], object] | None = None, cancel: CancelToken | None = None,
                   level: float = 0.0,
                   cell: float | None = None, precision: int | None = None,
                   traversal: Literal["continuation", "grid"] | None = None,
                   face_ambiguity: Literal["asymptotic_decider", "join_inside", "separate_inside"] | None = None,
                   seed_resolution: int | None = None, max_triangles: int | None = None,
                   threads: int | None = None) -> Mesh: ...
def marching_tetrahedra(field: _FieldLike, *, return_normals: bool = False,
                        progress: Callable[[float], object] | None = None, cancel: CancelToken | None = None,
                        level: float = 0.0,
                        cell: float | None = None, precision: int | None = None,
                        traversal: Literal["continuation", "grid"] | None = None,
                        seed_resolution: int | None = None, max_triangles: int | None = None,
                        threads: int | None = None) -> Mesh: ...
def curvature(field: _FieldLike, points: ArrayLike) -> dict[str, NDArray[np.float64]]: ...
def project(field: _FieldLike, points: ArrayLike, *, max_iterations: int | None = None,
            tolerance: float | None = None, max_step: float | None = None,
            max_travel: float | None = None) -> dict[str, NDArray[Any]]: ...
def trace_creases(field: _FieldLike, *, resolution: int | None = None, max_spacing: float | None = None,
                  min_spacing: float | None = None, max_turn: float | None = None) -> dict[str, Any]: ...
def corner_normals(field: _FieldLike, vertices: ArrayLike, faces: ArrayLike) -> NDArray[np.float64]: ...
def crease_angles(field: _FieldLike, vertices: ArrayLike, faces: ArrayLike, *,
                  near: float | None = None) -> dict[str, Any]: ...
def evaluate(field: _FieldLike, vertices: ArrayLike, faces: ArrayLike, *,
             normals: ArrayLike | Literal["field", "mesh"] | None = None, views: int = 8, resolution: int = 64,
             projection: Literal["perspective", "orthographic"] = "perspective",
             samples: int = 20000) -> dict[str, Any]: ...
