"""cdp.trace: a numpy function of points, run once on symbols, becomes an expression field.

    def f(p):                                   # p: (N, 3) float64 -> (N,)
        g = np.sin(6*p[:, 0])*np.cos(6*p[:, 1]) + ...
        return np.maximum(g / 6, np.linalg.norm(p, axis=1) - 1)
    field = cdp.trace(f, bounds=((-1.1,) * 3, (1.1,) * 3))

`trace(f, bounds)` calls f once with a stand-in for the (N, 3) array whose entries are symbols
(x, y, z), records what numpy does with them and writes the result as one formula of the
`expression` model (polygonizer/include/cdp/core/models/expression.h). The field it returns has
exact values, gradients and Hessians, knows every branch point of np.maximum, np.minimum,
np.abs, np.clip, .max(axis=1), ... (so the adaptive polygonizer follows the creases among them
and meshes the C1 seams of rounded and smooth shapes as smooth), and calls no Python while a mesh
is made. The formula is checked against f itself, called once on 1,241 points of the box (a 9^3
grid and 512 random points): values must agree to 1e-9 of their scale.

np.where(u < v, u, v) and the like (>, <=, >=; either order of the two values; u or v a
constant: np.where(d > 0, d, 0)) trace as the min or max they compute. Any other function that
decides on values (if, while, other comparisons and np.where, boolean masks), asks for
the number of points (len(p), p.shape, np.zeros(len(p))), or uses what is not listed below,
cannot be traced: TraceError says where. `cdp.callable_field(f, bounds)` traces first and uses
the function as a black box (called on every batch of points, derivatives by central
differences) when tracing fails or gradient= or hessian= are given; trace=False skips it.

What traces: the arithmetic operators (+ - * / ** %, unary -, @ with constant matrices); the
numpy functions add, subtract, multiply, divide, negative, power, square, sqrt, exp, log, sin,
cos, tan, arctan, arctan2, hypot, abs (absolute, fabs), maximum, minimum (fmax, fmin), clip,
floor, round (around, rint; halves away from zero, where numpy's go to even: the check against
the function samples 1,241 points and may miss a half the mesh meets; like floor and mod, its
jumps are no branch point, so where a repetition's copies meet across a cell's boundary the
crease there is not followed), mod (remainder), floor_divide, reciprocal; sinh,
cosh, log10, log2, exp2, expm1, log1p, deg2rad (radians), rad2deg (degrees), written with the
functions above (expm1 and log1p lose their precision near zero); sum, max, min (amax, amin), mean along a
coordinate axis (axis=1 or -1 of an (N, 3) array) as functions, methods or ufunc.reduce;
np.linalg.norm along a coordinate axis; np.dot, np.stack, np.column_stack; np.zeros_like,
np.ones_like and np.full_like (np.full_like(x, np.inf) starting a running np.minimum); indexing that keeps
the points' axis whole (p[:, 0], p[..., 1:], p[:, [2, 0, 1]]); p.T and unpacking x, y, z = p.T;
numpy constants of any shape that broadcasts against a point's (numbers, (3,), (1, 3), (3, 3)).
"""
import functools as _functools
import math as _math
import operator as _operator

import numpy as _np

from . import _cdp

__all__ = ["trace", "trace_formula", "TraceError"]


class TraceError(ValueError):
    """A function that cannot be traced: the message says what it did that tracing cannot follow."""


# ---------------------------------------------------------------------------------------------
# Scalar symbols: one per distinct value a traced function computes for a point. Numbers stay
# Python floats (folded as they meet), so a constant never becomes a node.

class _Node:
    __slots__ = ("op", "args", "__weakref__")

    def __init__(self, op, args=()):
        self.op = op
        self.args = args

    def __bool__(self):
        raise TraceError("the function decides on the points' values (if, while, a comparison, np.where or a "
                         "boolean mask): tracing follows arithmetic only")

    # Numpy's object arrays apply Python operators to their elements.
    def __add__(self, o): return _apply("+", self, o)
    def __radd__(self, o): return _apply("+", o, self)
    def __sub__(self, o): return _apply("-", self, o)
    def __rsub__(self, o): return _apply("-", o, self)
    def __mul__(self, o): return _apply("*", self, o)
    def __rmul__(self, o): return _apply("*", o, self)
    def __truediv__(self, o): return _apply("/", self, o)
    def __rtruediv__(self, o): return _apply("/", o, self)
    def __neg__(self): return _apply("neg", self)
    def __pos__(self): return self

    # Comparisons np.where may read come through _Points (_ORDERINGS); one of single values decides.
    def _compare(self, o):
        _refuse_comparison()

    __lt__ = __le__ = __gt__ = __ge__ = _compare
    __hash__ = object.__hash__


def _refuse_comparison():
    raise TraceError("the function compares values of the points (<, >, ==) other than to take the smaller or "
                     "larger of the two (np.where(u < v, u, v)): tracing follows arithmetic only")


class _Comparison:
    """lesser < greater (or <=) for one point, kept only to be read by np.where: a tie of the
    two gives the same value on either side, so < and <= trace alike."""
    __slots__ = ("lesser", "greater")

    def __init__(self, lesser, greater):
        self.lesser, self.greater = lesser, greater

    def __bool__(self):
        _refuse_comparison()

    __float__ = __bool__


def _same(a, b):
    """Whether a and b compute the same value the same way: the same node, or nodes of one
    operation on the same operands (q.max(axis=1) written twice), or equal numbers."""
    pairs = [(a, b)]
    seen = set()
    while pairs:
        u, v = pairs.pop()
        if u is v or (id(u), id(v)) in seen:
            continue
        seen.add((id(u), id(v)))
        if _is_number(u) or _is_number(v):
            if not (_is_number(u) and _is_number(v) and float(u) == float(v)):
                return False
            continue
        if u.op != v.op or len(u.args) != len(v.args):
            return False
        pairs.extend(zip(u.args, v.args))
    return True


def _choose(c, a, b):
    """np.where for one point: a where c holds, else b; a traced comparison only as a min or max."""
    if isinstance(c, (bool, _np.bool_)):
        return a if c else b
    if not isinstance(c, _Comparison):
        _refuse_comparison()
    if _same(a, c.lesser) and _same(b, c.greater):
        return _apply("min", a, b)
    if _same(a, c.greater) and _same(b, c.lesser):
        return _apply("max", a, b)
    _refuse_comparison()


X, Y, Z = _Node("x"), _Node("y"), _Node("z")

_FOLD = {
    "+": _operator.add, "-": _operator.sub, "*": _operator.mul, "/": _operator.truediv, "neg": _operator.neg,
    "pow": _math.pow, "sqrt": _math.sqrt, "exp": _math.exp, "log": _math.log, "sin": _math.sin, "cos": _math.cos,
    "tan": _math.tan, "atan": _math.atan, "atan2": _math.atan2, "abs": abs, "floor": _math.floor,
    "min": min, "max": max, "mod": lambda a, b: a - b * _math.floor(a / b),
    "round": lambda a: _math.copysign(_math.floor(abs(a) + 0.5), a),
}


def _is_number(v):
    return not isinstance(v, _Node)


def _apply(op, *args):
    """The node op(args), or its value when every argument is a number. Numpy scalars become
    floats; a non-finite constant ends the trace (the formula has no way to write it)."""
    args = tuple(a if isinstance(a, _Node) else _float(a) for a in args)
    if all(_is_number(a) for a in args):
        try:
            return float(_FOLD[op](*args))
        except (ValueError, ZeroDivisionError, OverflowError):
            raise TraceError(f"the constant {op}{args} has no finite value") from None
    # Identities that keep the formula as small as the function's text.
    if op == "+":
        if _is_number(args[0]) and args[0] == 0.0: return args[1]
        if _is_number(args[1]) and args[1] == 0.0: return args[0]
    if op == "-" and _is_number(args[1]) and args[1] == 0.0:
        return args[0]
    if op == "*":
        for a, b in (args, args[::-1]):
            if _is_number(a) and a == 1.0: return b
    if op == "/" and _is_number(args[1]) and args[1] == 1.0:
        return args[0]
    if op in ("min", "max"):  # min(min(a, b), c) is min(a, b, c): one branch point fewer
        neutral = _math.inf if op == "min" else -_math.inf  # min(inf, a) is a
        flat = []
        for a in args:
            flat.extend(a.args if isinstance(a, _Node) and a.op == op else (a,))
        args = tuple(a for a in flat if not (_is_number(a) and a == neutral))
        if len(args) == 1:
            return args[0]
    return _Node(op, args)


def _float(v):
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise TraceError(f"the function combined the points with {type(v).__name__} {v!r}") from None
    if _math.isnan(f):
        raise TraceError("the function uses the constant nan, which a formula cannot hold")
    return f  # an infinity may start a running min or max (np.full_like(x, np.inf)); _number refuses the rest


def _power(a, b):
    if _is_number(b):
        if b == 1.0: return a
        if b == 0.5: return _apply("sqrt", a)
    return _apply("pow", a, b)


def _scalar(op):
    return lambda *args: _apply(op, *args)


def _hypot(a, b):
    return _apply("sqrt", _apply("+", _apply("*", a, a), _apply("*", b, b)))


def _sinh_cosh(sign):
    return lambda a: _apply("*", 0.5, _apply("+" if sign > 0 else "-", _apply("exp", a), _apply("exp", _apply("neg", a))))


def _clip(u, lo, hi):
    if lo is not None: u = _apply("max", u, lo)
    if hi is not None: u = _apply("min", u, hi)
    return u


_UFUNCS = {
    _np.add: _scalar("+"), _np.subtract: _scalar("-"), _np.multiply: _scalar("*"), _np.true_divide: _scalar("/"),
    _np.negative: _scalar("neg"), _np.positive: lambda a: a, _np.power: _power, _np.float_power: _power,
    _np.square: lambda a: _apply("pow", a, 2.0), _np.sqrt: _scalar("sqrt"), _np.exp: _scalar("exp"),
    _np.log: _scalar("log"), _np.sin: _scalar("sin"), _np.cos: _scalar("cos"), _np.tan: _scalar("tan"),
    _np.arctan: _scalar("atan"), _np.arctan2: _scalar("atan2"), _np.hypot: _hypot, _np.absolute: _scalar("abs"),
    _np.fabs: _scalar("abs"), _np.maximum: _scalar("max"), _np.minimum: _scalar("min"), _np.fmax: _scalar("max"),
    _np.fmin: _scalar("min"), _np.floor: _scalar("floor"), _np.mod: _scalar("mod"),
    _np.floor_divide: lambda a, b: _apply("floor", _apply("/", a, b)),
    _np.reciprocal: lambda a: _apply("/", 1.0, a),
    # Halves away from zero (the expression's round, std::round) where numpy's go to the even
    # neighbour: the two differ only at exact halves, where a repetition's cells meet and the
    # check against the function says so if the field differs there.
    _np.rint: _scalar("round"),
    # Written with the expression's own functions (it has no hyperbolic functions). Not tanh
    # (exp(2a) overflows past a = 355, and its derivative with it: NaN where numpy's is 0) nor
    # arcsin and arccos (sqrt(1 - a^2)'s derivative is NaN wherever a clip holds a at 1).
    _np.sinh: _sinh_cosh(-1), _np.cosh: _sinh_cosh(1),
    _np.log10: lambda a: _apply("/", _apply("log", a), _math.log(10.0)),
    _np.log2: lambda a: _apply("/", _apply("log", a), _math.log(2.0)),
    _np.exp2: lambda a: _apply("exp", _apply("*", a, _math.log(2.0))),
    _np.expm1: lambda a: _apply("-", _apply("exp", a), 1.0), _np.log1p: lambda a: _apply("log", _apply("+", 1.0, a)),
    _np.deg2rad: lambda a: _apply("*", a, _math.pi / 180), _np.radians: lambda a: _apply("*", a, _math.pi / 180),
    _np.rad2deg: lambda a: _apply("*", a, 180 / _math.pi), _np.degrees: lambda a: _apply("*", a, 180 / _math.pi),
}
# Comparisons np.where may read: (lesser, greater, strict) of the operands as given.
_ORDERINGS = {_np.less: lambda u, v: (u, v, True), _np.less_equal: lambda u, v: (u, v, False),
              _np.greater: lambda u, v: (v, u, True), _np.greater_equal: lambda u, v: (v, u, False)}
_COMPARISONS = {_np.equal, _np.not_equal, _np.isnan, _np.isfinite, _np.isinf, _np.logical_and, _np.logical_or,
                _np.logical_not, _np.sign}
_REDUCE = {_np.add: "+", _np.multiply: "*", _np.maximum: "max", _np.minimum: "min", _np.fmax: "max",
           _np.fmin: "min"}


# ---------------------------------------------------------------------------------------------
# Arrays of symbols: what the function sees instead of its (N, 3) array. The points' axis (of
# unknown length) is left out of the object array `a` and stands first, or last after .T.

class _Points(_np.lib.mixins.NDArrayOperatorsMixin):
    __array_priority__ = 1000

    def __init__(self, a, last=False):
        self.a = _np.asarray(a, dtype=object)
        self.last = last  # the points' axis is the last one (p.T)

    # What cannot be known: the number of points.
    def _unknown(self, *args, **kwargs):
        raise TraceError("the function asks for the number of points (len, shape, size, reshape): tracing runs on "
                         "symbols, not on a given number of points")

    def __len__(self):
        if self.last and self.a.ndim == 1:
            return len(self.a)  # x, y, z = p.T
        self._unknown()

    def __bool__(self):
        return bool(_Node(None))  # raises: a decision on values

    shape = property(_unknown)
    size = property(_unknown)
    reshape = _unknown

    @property
    def ndim(self):
        return self.a.ndim + 1

    @property
    def dtype(self):
        return _np.dtype(float)

    @property
    def T(self):
        if self.a.ndim != 1:
            raise TraceError("the function transposes an array of more than two axes")
        return _Points(self.a, last=not self.last)

    def astype(self, *args, **kwargs):
        return self

    def copy(self):
        return self

    def __iter__(self):
        if not self.last or self.a.ndim != 1:
            raise TraceError("the function iterates over the points (a loop over p or p[i]): tracing follows "
                             "whole-array operations only")
        return (_Points(v) for v in self.a)

    def __getitem__(self, key):
        key = key if isinstance(key, tuple) else (key,)
        if self.last:
            if len(key) == 2 and key[1] == slice(None):
                return _Points(self.a[key[0]])
            if len(key) == 1 and not isinstance(key[0], slice):
                return _Points(self.a[key[0]])
        else:
            if key and key[0] is Ellipsis:
                return _Points(self.a[key])
            if key and key[0] == slice(None):
                return _Points(self.a[key[1:]])
        raise TraceError(f"the function indexes the points' axis ({key!r}): tracing keeps every point and indexes "
                         "coordinates only (p[:, 0], p[..., 1:])")

    def __setitem__(self, key, value):
        raise TraceError("the function assigns into an array (p[...] = ...): tracing follows expressions only")

    # Reductions along a coordinate axis.
    def _axis(self, axis):
        if axis is None:
            raise TraceError("the function reduces over all the points (axis=None): reduce along axis=1")
        if self.last:
            raise TraceError("the function reduces a transposed array")
        axis = axis + self.ndim if axis < 0 else axis
        if axis == 0 or axis >= self.ndim:
            raise TraceError(f"the function reduces along axis {axis}: tracing reduces along coordinates only")
        return axis - 1

    def _reduce(self, op, axis, keepdims=False, **kwargs):
        if kwargs.get("out") is not None or kwargs.get("where", True) is not True or "initial" in kwargs:
            raise TraceError("a reduction with out=, where= or initial= cannot be traced")
        k = self._axis(axis)
        a = _np.moveaxis(self.a, k, -1)
        if a.shape[-1] == 0:
            raise TraceError("the function reduces an empty axis")
        out = _np.empty(a.shape[:-1], dtype=object)
        for i in _np.ndindex(out.shape):
            out[i] = _functools.reduce(lambda u, v: _apply(op, u, v), a[i])
        return _Points(_np.expand_dims(out, k) if keepdims else out)

    def sum(self, axis=None, **kwargs):
        return self._reduce("+", axis, **kwargs)

    def max(self, axis=None, **kwargs):
        return self._reduce("max", axis, **kwargs)

    def min(self, axis=None, **kwargs):
        return self._reduce("min", axis, **kwargs)

    def prod(self, axis=None, **kwargs):
        return self._reduce("*", axis, **kwargs)

    def mean(self, axis=None, **kwargs):
        n = self.a.shape[self._axis(axis)]
        return self._reduce("+", axis, **kwargs) / float(n)

    def __array__(self, *args, **kwargs):
        raise TraceError("the function turns the points into a plain numpy array (np.asarray, np.array, a "
                         "function that numpy cannot hand to the symbols)")

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if kwargs.get("out") is not None or kwargs.get("where", True) is not True:
            raise TraceError(f"np.{ufunc.__name__} with out= or where= cannot be traced")
        if method == "reduce":
            if ufunc not in _REDUCE or not isinstance(inputs[0], _Points):
                raise TraceError(f"np.{ufunc.__name__}.reduce cannot be traced")
            kwargs.setdefault("axis", 0)
            return inputs[0]._reduce(_REDUCE[ufunc], kwargs.pop("axis"), **kwargs)
        if method != "__call__":
            raise TraceError(f"np.{ufunc.__name__}.{method} cannot be traced")
        if ufunc is _np.matmul:
            return _matmul(*inputs)
        if ufunc in _ORDERINGS:
            order = _ORDERINGS[ufunc]
            return _Decisions(_np.frompyfunc(lambda u, v: _comparison(*order(u, v)), 2, 1)(*_operands(inputs)))
        if ufunc in _COMPARISONS:
            _refuse_comparison()
        if ufunc not in _UFUNCS:
            raise TraceError(f"np.{ufunc.__name__} cannot be traced (see cdp.trace's documentation for what can)")
        arrays = _operands(inputs)
        return _Points(_np.frompyfunc(_UFUNCS[ufunc], len(arrays), 1)(*arrays))

    def __array_function__(self, function, types, args, kwargs):
        handler = _FUNCTIONS.get(function)
        if handler is None:
            raise TraceError(f"np.{function.__name__} cannot be traced (see cdp.trace's documentation for what can)")
        return handler(*args, **kwargs)


def _comparison(lesser, greater, strict):
    """One point's comparison: a bool where both sides are numbers (a constant column), else
    kept for np.where, where a tie gives the same value on either side."""
    if _is_number(lesser) and _is_number(greater):
        return bool(lesser < greater) if strict else bool(lesser <= greater)
    return _Comparison(lesser, greater)


class _Decisions:
    """An array of comparisons of the points' values, good only as np.where's condition: anything
    else done with it (a mask, .all(), np.logical_and, if) decides on values."""
    __array_priority__ = 1001

    def __init__(self, a):
        self.a = a

    def __bool__(self):
        _refuse_comparison()

    def __getattr__(self, name):
        _refuse_comparison()

    def __getitem__(self, key):
        _refuse_comparison()

    def __array__(self, *args, **kwargs):
        _refuse_comparison()

    def __array_ufunc__(self, *args, **kwargs):
        _refuse_comparison()

    def __array_function__(self, function, types, args, kwargs):
        if function is not _np.where:
            _refuse_comparison()
        return _where(*args, **kwargs)


def _where(condition, a=None, b=None):
    if a is None or b is None or not isinstance(condition, _Decisions):
        _refuse_comparison()
    if isinstance(a, _Decisions) or isinstance(b, _Decisions):
        _refuse_comparison()
    values = _operands((a, b, _Points(condition.a)))
    return _Points(_np.frompyfunc(lambda u, v, c: _choose(c, u, v), 3, 1)(*values))


def _operand(v):
    """An operand as an object array over a point's axes: a constant with the points' axis of
    length 1 in front ((1, 3)) loses it; a transposed array cannot mix with others."""
    if isinstance(v, _Points):
        if v.last:
            raise TraceError("the function combines a transposed array (p.T) with others: unpack it (x, y, z = p.T) "
                             "or index it first")
        return v.a
    c = _np.asarray(v, dtype=float)
    return c.astype(object)


def _operands(inputs):
    """The operands of one operation; a constant as long as the points' full shape ((1, 3)
    beside (N, 3)) has that axis of length 1 in front and loses it."""
    full = max(v.ndim for v in inputs if isinstance(v, _Points))
    out = []
    for v in inputs:
        a = _operand(v)
        if not isinstance(v, _Points) and a.ndim >= full:
            if a.ndim > full or a.shape[0] != 1:
                raise TraceError(f"the function combines the points with a constant of shape {a.shape}, which has "
                                 "a value per point: tracing takes constants the same for every point")
            a = a[0]
        out.append(a)
    return out


def _matmul(a, b):
    if isinstance(a, _Points) and not isinstance(b, _Points) and not a.last:
        return _Points(_np.matmul(a.a, _np.asarray(b, dtype=float).astype(object)))
    raise TraceError("the function multiplies matrices other than points @ constant matrix")


def _points_only(name):
    def check(v):
        if not isinstance(v, _Points):
            raise TraceError(f"np.{name} of something other than the points' arrays")
        return v
    return check


def _norm(x, ord=None, axis=None, keepdims=False):
    if ord not in (None, 2) or keepdims:
        raise TraceError("np.linalg.norm traces with the default ord and keepdims only")
    return _np.sqrt((x * x).sum(axis=axis))


def _stack(arrays, axis=0):
    arrays = [_operand(v) if isinstance(v, _Points) else None for v in arrays]
    if any(a is None for a in arrays) or any(a.ndim != 0 for a in arrays):
        raise TraceError("np.stack traces for arrays of one value per point only")
    if axis in (1, -1):
        return _Points(_np.array([a[()] for a in arrays], dtype=object))
    if axis == 0:
        return _Points(_np.array([a[()] for a in arrays], dtype=object), last=True)
    raise TraceError(f"np.stack with axis={axis} cannot be traced")


def _round(a, decimals, kwargs):
    if decimals != 0 or kwargs.get("out") is not None:
        raise TraceError("np.round traces with decimals=0 and without out= only")
    return _np.rint(a)


def _clip_array(a, a_min=None, a_max=None, **kwargs):
    if kwargs:
        raise TraceError("np.clip with out= cannot be traced")
    arrays = _operands((a, 0.0 if a_min is None else a_min, 0.0 if a_max is None else a_max))
    lo_given, hi_given = a_min is not None, a_max is not None
    return _Points(_np.frompyfunc(lambda u, lo, hi: _clip(u, lo if lo_given else None, hi if hi_given else None),
                                  3, 1)(*arrays))


def _like(fill):
    def make(a, *args, **kwargs):
        if not isinstance(a, _Points) or kwargs.get("shape") is not None:
            raise TraceError("np.*_like of something other than the points' arrays, or with shape=")
        value = fill if fill is not None else (args[0] if args else kwargs.get("fill_value"))
        out = _np.empty(a.a.shape, dtype=object)
        out.fill(_float(value))
        return _Points(out, last=a.last)
    return make


_FUNCTIONS = {
    _np.linalg.norm: _norm,
    _np.sum: lambda a, axis=None, **k: _points_only("sum")(a).sum(axis, **k),
    _np.max: lambda a, axis=None, **k: _points_only("max")(a).max(axis, **k),
    _np.min: lambda a, axis=None, **k: _points_only("min")(a).min(axis, **k),
    _np.amax: lambda a, axis=None, **k: _points_only("amax")(a).max(axis, **k),
    _np.amin: lambda a, axis=None, **k: _points_only("amin")(a).min(axis, **k),
    _np.mean: lambda a, axis=None, **k: _points_only("mean")(a).mean(axis, **k),
    _np.prod: lambda a, axis=None, **k: _points_only("prod")(a).prod(axis, **k),
    _np.clip: _clip_array,
    _np.zeros_like: _like(0.0),
    _np.ones_like: _like(1.0),
    _np.full_like: _like(None),
    _np.dot: lambda a, b: _matmul(a, b),
    _np.stack: _stack,
    _np.column_stack: lambda arrays: _stack(arrays, axis=1),
    _np.where: _where,
    _np.round: lambda a, decimals=0, **k: _round(a, decimals, k),
    _np.around: lambda a, decimals=0, **k: _round(a, decimals, k),
}


# ---------------------------------------------------------------------------------------------
# Formula text: every node reached more than once is named ("define"), so a shared value is
# computed once and a shared min, max or abs is one branch point, not one per use.

_PRECEDENCE = {"+": 1, "-": 1, "*": 2, "/": 2, "neg": 3}
_FUNCTION_NAME = {"pow": "pow", "sqrt": "sqrt", "exp": "exp", "log": "log", "sin": "sin", "cos": "cos", "tan": "tan",
                  "atan": "atan", "atan2": "atan2", "abs": "abs", "floor": "floor", "min": "min", "max": "max",
                  "mod": "mod", "round": "round"}
_MAX_DEFINITIONS = 256  # the expression model's limit (kMaxDefinitions in expression.cpp)


def _number(v):
    if not _math.isfinite(v):
        raise TraceError(f"the function's result uses the constant {v!r}, which a formula cannot hold")
    return repr(v) if v >= 0 else f"({v!r})"


def _is_cheap(node):
    """Arithmetic on the coordinates and numbers: cheaper to repeat than to name (the names
    are limited), and without a branch point to share."""
    return node.op in _PRECEDENCE and all(not isinstance(a, _Node) or a.op in ("x", "y", "z") for a in node.args)


def _render(root):
    uses = {}
    order = []  # children before parents
    stack = [(root, False)]
    while stack:  # without recursion: a long sum is deep
        node, done = stack.pop()
        if not isinstance(node, _Node):
            continue
        if done:
            order.append(node)
            continue
        uses[id(node)] = uses.get(id(node), 0) + 1
        if uses[id(node)] == 1:
            stack.append((node, True))
            stack.extend((a, False) for a in reversed(node.args))
    define = {}
    text = {}
    branching = {}  # whether a node's value passes through a min, max or abs

    def operand(a, precedence, right=False):
        if not isinstance(a, _Node):
            return _number(a)
        t, p = text[id(a)]
        return f"({t})" if p < precedence or (right and p == precedence) else t

    for node in order:
        op, args = node.op, node.args
        if op in ("x", "y", "z"):
            text[id(node)] = (op, 9)
            branching[id(node)] = False
            continue
        branching[id(node)] = op in ("min", "max", "abs") or any(
            isinstance(a, _Node) and branching[id(a)] for a in args)
        if op in ("+", "-", "*", "/"):
            p = _PRECEDENCE[op]
            t = f"{operand(args[0], p)} {op} {operand(args[1], p, right=True)}"
        elif op == "neg":
            p = 3
            t = f"-{operand(args[0], 4)}"
        else:
            p = 9
            t = f"{_FUNCTION_NAME[op]}({', '.join(operand(a, 0) for a in args)})"
        if uses[id(node)] > 1 and node is not root and (branching[id(node)] or not _is_cheap(node)):
            name = f"_t{len(define)}"
            define[name] = t
            t, p = name, 9
        text[id(node)] = (t, p)
    if len(define) > _MAX_DEFINITIONS:
        raise TraceError(f"the function computes {len(define)} values used more than once; an expression holds at "
                         f"most {_MAX_DEFINITIONS} named ones")
    return (text[id(root)][0] if isinstance(root, _Node) else _number(root)), define


def trace_formula(f):
    """(formula, definitions) of the expression that f computes for a point, as for the JSON keys
    "value" and "define" of an expression field. Raises TraceError when f cannot be traced."""
    try:
        out = f(_Points(_np.array([X, Y, Z], dtype=object)))
    except TraceError:
        raise
    except Exception as e:  # whatever the function raised on symbols: it cannot be traced
        raise TraceError(f"the function raised {type(e).__name__} on symbols: {e}") from None
    if isinstance(out, _Points):
        if out.last or out.a.size != 1 or out.a.ndim > 1:  # (N,) or (N, 1), as callable_field takes
            raise TraceError("the function returns more than one value per point: it must return an (N,) array")
        out = out.a.reshape(())[()]
    elif not isinstance(out, _Node):
        raise TraceError(f"the function returns {type(out).__name__}, not an array computed from the points")
    if _is_number(out):
        raise TraceError("the function returns a constant: it has no surface")
    return _render(out)


# The check against the function itself: a 9^3 grid of the box (its corners and faces, where
# the surface often is not, and its middle) and 512 points drawn with a fixed seed.
_CHECK_GRID = 9
_CHECK_RANDOM = 512
_CHECK_SEED = 20261129
# Agreement asked of the formula: the function's own arithmetic in a different order (numpy's
# pairwise sums, libm against the evaluator's) differs by a few ulps of the largest terms.
_CHECK_RELATIVE = 1e-9


def trace(f, bounds, check=True):
    """An expression field (cdp.Field) computing what the numpy function f computes, with exact
    derivatives and its branch points known; bounds ((xmin, ymin, zmin), (xmax, ymax, zmax)).
    check: compare the field with f on 1,241 points of the box (one call of f) and raise
    TraceError where they differ (a function whose arithmetic depends on the number of points).
    Raises TraceError when f cannot be traced (the message says why)."""
    formula, define = trace_formula(f)
    try:
        field = _cdp.expression(formula, bounds, define=define or None)
    except ValueError as e:
        raise TraceError(f"the traced formula is not an expression the model accepts: {e}") from None
    if check:
        lo, hi = _np.asarray(bounds[0], dtype=float), _np.asarray(bounds[1], dtype=float)
        t = _np.linspace(0.0, 1.0, _CHECK_GRID)
        grid = _np.stack(_np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
        rng = _np.random.default_rng(_CHECK_SEED)
        points = lo + _np.concatenate([grid, rng.random((_CHECK_RANDOM, 3))]) * (hi - lo)
        expected = _np.asarray(f(points.copy()), dtype=float).reshape(-1)
        got = field.values(points)
        if expected.shape != got.shape:
            raise TraceError(f"the function returns {expected.shape[0]} values for {len(points)} points")
        scale = 1.0 + _np.nanmax(_np.abs(expected)) if _np.isfinite(expected).any() else 1.0
        same = (_np.abs(expected - got) <= _CHECK_RELATIVE * scale) | (_np.isnan(expected) & _np.isnan(got))
        if not same.all():
            i = int(_np.argmin(same))
            raise TraceError(f"the traced formula gives {got[i]!r} at {tuple(points[i])} where the function gives "
                             f"{expected[i]!r}: the function's arithmetic depends on more than each point")
    return field
