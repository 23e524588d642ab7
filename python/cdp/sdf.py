"""cdp.sdf: signed distance models written like fogleman/sdf, compiled to expression fields.

    from cdp.sdf import *
    f = sphere(1) & box(1.5)
    c = cylinder(0.5)
    f -= c.orient(X) | c.orient(Y) | c.orient(Z)
    V, F, _, stats = cdp.polygonize(f, tolerance=1e-3)     # or f.field(), f.to_json(), f.save("f.json")

A model is an immutable tree of `SDF` nodes. Nothing is evaluated in Python: the tree renders to
one formula of the `expression` model (`polygonizer/include/cdp/core/models/expression.h`) with
named sub-expressions (its `"define"` key), so values, gradients and Hessians are exact (automatic
differentiation in C++) and every `min`, `max`, `abs` and `clamp` of the model is a branch point
the adaptive polygonizer knows (it meshes along the sharp creases among them). The formula grows
linearly with the model: a value used more than once (the operands of a smooth union, a node
shared by two parents with the same coordinates) is named once, and so are transformed
coordinates (`_p0 = 0.97*x + 0.18*y - 0.16*z + 2.8`), which the transformed child then reads
instead of x, y, z; a formula defined twice gets one name. Consecutive affine transforms
(translate, rotate, orient, scale) compose into one; unions (intersections, differences) in a
row are one n-ary min (max).

Conventions (where fogleman/sdf leaves a choice, or where ours differs):

- Negative inside, positive outside; 3D only; vectors are any 3-sequences (tuples, lists, numpy
  arrays), scalars where a size may be one number for all three axes.
- Sharp edges are `max` forms, which the mesher follows as creases: `box` is
  max(|x| - sx/2, |y| - sy/2, |z| - sz/2), `capped_cylinder` and `capped_cone` likewise: exact
  distances inside and wherever the nearest point is on a face, a lower bound (still 1-Lipschitz)
  near edges and corners outside. `rounded_box` and `rounded_cylinder` are Inigo Quilez's exact
  distances, written so that the gradient is finite in the interior too (the formulas'
  sqrt(|max(q, 0)|^2) is 0 with an infinite derivative inside the core box; we use
  hypot(max(q, 0), min(m, 0)) + 2 min(m, 0) with m = max(q), the same values).
- `plane(normal, point)` is solid on the side the normal points to, as in fogleman/sdf
  (F = (point - p) . normal); `slab` bounds coordinates from both sides.
- `rotate(angle, vector)` turns the shape by `angle` radians about `vector` (right-hand rule);
  `orient(axis)` turns the shape's +Z axis onto `axis`. Matrix entries within 1e-15 of 0 or +-1
  are snapped to them, so quarter turns are exact permutations.
- `scale(factor)` with one factor is exact (F(p / s) s); with three it multiplies by the
  smallest, which keeps a bound on the distance but not the distance (as fogleman/sdf).
- `repeat(spacing, count=None, padding=0)` uses p - s round(p / s) (clamped to +-count). The mesher
  cannot see the jumps of round: a copy must not reach the edge of its cell, where the field
  jumps to the next copy. `padding=1` with a count is the union of the translated copies (no
  round: copies may overlap); without one, the min over the neighbouring copies (3 copies of
  the child per repeated axis), continuous across the cell edges, but copies that meet there
  meet on the jump of round, where the mesher may fail.
- `twist(k)` and `bend(k)` are not distance-preserving: the field's slope grows with the distance
  from the axis (fine for the mesher, which projects with Newton steps, but not a distance).
- Smooth operations (`k=`): Inigo Quilez's polynomial smooth min, as fogleman/sdf writes it:
  h = clamp(0.5 + 0.5 (b - a) / k, 0, 1), union = b + (a - b) h - k h (1 - h); intersection and
  difference the mirrored forms. The blend is C1 where h reaches 0 or 1 (branch points of the
  clamp). `a | b.k(0.2)` smooths with the right operand's k, as in fogleman/sdf.
- Bounding boxes are conservative and may be infinite (`cylinder`, `plane`, `slab` with open
  sides, `repeat` without count, `negate`): union is the box union, intersection the box
  intersection, difference the left box; smooth unions grow by k, dilate and shell by their
  amount; transforms map the box's corners (interval arithmetic, so infinite sides stay where
  they are). `field()`, `to_json()`, `save()` pad the box by `pad` times its longest side on every
  side, and raise ValueError on an infinite or empty box unless `bounds=` is given (used as is).
- Limits of the expression model: at most 256 named sub-expressions in use (about one per
  transform with rotation, smooth operation or shared node), and about a hundred levels of
  nesting (a deeper model is a ValueError "nested too deeply" from the C++ parser).
"""
import copy as _copy
import json as _json
import math as _math
import os as _os
import re as _re

from . import _cdp

__all__ = [
    "SDF", "Vector", "X", "Y", "Z", "UP", "ORIGIN",
    "sphere", "box", "rounded_box", "torus", "capsule", "cylinder", "capped_cylinder", "rounded_cylinder",
    "capped_cone", "plane", "slab", "ellipsoid", "octahedron", "tetrahedron",
    "union", "intersection", "difference", "blend", "negate", "shell", "dilate", "erode",
    "translate", "scale", "rotate", "orient", "repeat", "twist", "bend",
]


class Vector(tuple):
    """A 3-vector that adds, subtracts, negates and scales as fogleman/sdf's numpy constants do
    (-X, X + Y, 2 * Z) and is a plain tuple otherwise. Any 3-sequence is accepted where a
    vector is expected."""

    __slots__ = ()

    def __new__(cls, x, y=None, z=None):
        v = (x, y, z) if y is not None else tuple(x)
        return super().__new__(cls, (float(c) for c in v))

    def __neg__(self):
        return Vector(-c for c in self)

    def __pos__(self):
        return self

    def __add__(self, other):
        return Vector(a + b for a, b in zip(self, _vec3(other, "Vector +")))

    __radd__ = __add__

    def __sub__(self, other):
        return Vector(a - b for a, b in zip(self, _vec3(other, "Vector -")))

    def __rsub__(self, other):
        return Vector(b - a for a, b in zip(self, _vec3(other, "Vector -")))

    def __mul__(self, f):
        return Vector(c * float(f) for c in self)

    __rmul__ = __mul__

    def __truediv__(self, f):
        return Vector(c / float(f) for c in self)

    def __repr__(self):
        return f"Vector({self[0]!r}, {self[1]!r}, {self[2]!r})"


X = Vector(1, 0, 0)
Y = Vector(0, 1, 0)
Z = Vector(0, 0, 1)
UP = Z
ORIGIN = Vector(0, 0, 0)

_INF = float("inf")
_UNBOUNDED = ((-_INF, -_INF, -_INF), (_INF, _INF, _INF))
_EMPTY = ((_INF, _INF, _INF), (-_INF, -_INF, -_INF))


# ---------------------------------------------------------------------------------------------
# Numbers, vectors, matrices (pure Python: a model is small).

def _scalar(v, what):
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise TypeError(f"{what}: expected a number, found {v!r}") from None
    if not _math.isfinite(f):
        raise ValueError(f"{what}: must be finite, found {f!r}")
    return f


def _positive(v, what):
    f = _scalar(v, what)
    if f <= 0:
        raise ValueError(f"{what}: must be positive, found {f!r}")
    return f


def _vec3(v, what, allow_scalar=False):
    if allow_scalar:
        try:
            f = float(v)
        except (TypeError, ValueError):
            pass
        else:
            return (_scalar(f, what),) * 3
    try:
        items = list(v)
    except TypeError:
        raise TypeError(f"{what}: expected 3 numbers, found {v!r}") from None
    if len(items) != 3:
        raise ValueError(f"{what}: expected 3 numbers, found {len(items)}")
    return tuple(_scalar(c, what) for c in items)


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _norm(a):
    return _math.sqrt(_dot(a, a))


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _normalize(v, what):
    n = _norm(v)
    if n == 0:
        raise ValueError(f"{what}: must not be the zero vector")
    return (v[0] / n, v[1] / n, v[2] / n)


_IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _matmul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3))


def _matvec(m, v):
    return tuple(m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] for i in range(3))


def _transpose(m):
    return tuple(tuple(m[j][i] for j in range(3)) for i in range(3))


def _snap(m):
    """Entries within 1e-15 (relative to their row) of 0 or +-1 become exactly that."""
    out = []
    for row in m:
        big = max(abs(v) for v in row) or 1.0
        r = []
        for v in row:
            if abs(v) < 1e-15 * big:
                v = 0.0
            elif abs(abs(v) - 1.0) < 1e-15:
                v = _math.copysign(1.0, v)
            r.append(v)
        out.append(tuple(r))
    return tuple(out)


def _rotation(angle, axis):
    """Rodrigues: the rotation by angle about the unit axis (right-hand rule)."""
    return _rotation_cs(_math.cos(angle), _math.sin(angle), axis)


def _rotation_cs(c, s, k):
    x, y, z = k
    m = 1.0 - c
    return _snap((
        (c + m * x * x, m * x * y - s * z, m * x * z + s * y),
        (m * x * y + s * z, c + m * y * y, m * y * z - s * x),
        (m * x * z - s * y, m * y * z + s * x, c + m * z * z),
    ))


def _rotation_z_to(axis):
    """The rotation that takes +Z onto the unit vector axis (about Z x axis)."""
    c = axis[2]
    w = _cross(Z, axis)
    s = _norm(w)
    if s < 1e-15:
        return _IDENTITY if c > 0 else _rotation_cs(-1.0, 0.0, X)  # half turn about X
    return _rotation_cs(c, s, (w[0] / s, w[1] / s, w[2] / s))


# ---------------------------------------------------------------------------------------------
# Boxes: ((xmin, ymin, zmin), (xmax, ymax, zmax)), sides possibly infinite.

def _box_union(a, b):
    return (tuple(map(min, a[0], b[0])), tuple(map(max, a[1], b[1])))


def _box_intersection(a, b):
    return (tuple(map(max, a[0], b[0])), tuple(map(min, a[1], b[1])))


def _box_inflate(b, r):
    return (tuple(v - r for v in b[0]), tuple(v + r for v in b[1]))


def _box_is_finite(b):
    return all(_math.isfinite(v) for v in b[0] + b[1])


def _box_is_empty(b):
    return any(lo > hi for lo, hi in zip(*b))


def _box_affine(b, m, t):
    """The box of {m c + t : c in b} (interval arithmetic: exact for a box, and a zero entry
    of m keeps an infinite side out). An empty box stays empty."""
    if _box_is_empty(b):
        return _EMPTY
    lo, hi = [], []
    for i in range(3):
        a, z = t[i], t[i]
        for j in range(3):
            if m[i][j] == 0.0:
                continue
            p, q = m[i][j] * b[0][j], m[i][j] * b[1][j]
            a += min(p, q)
            z += max(p, q)
        lo.append(a)
        hi.append(z)
    return (tuple(lo), tuple(hi))


def _box_radial(b, axes):
    """The box of everything a rotation about the other axis (in the plane of `axes`) can make
    of b: the two axes span +-the largest radius, the third is kept."""
    if _box_is_empty(b):
        return _EMPTY
    r = _math.hypot(max(abs(b[0][axes[0]]), abs(b[1][axes[0]])), max(abs(b[0][axes[1]]), abs(b[1][axes[1]])))
    lo, hi = list(b[0]), list(b[1])
    for a in axes:
        lo[a], hi[a] = -r, r
    return (tuple(lo), tuple(hi))


# ---------------------------------------------------------------------------------------------
# Formula text.

_NAME = _re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_NUMBER = _re.compile(r"[0-9][0-9.]*(e[+-]?[0-9]+)?\Z")


def _num(v):
    """A number as formula text: repr (the shortest decimals that read back as the same
    double), negatives in parentheses (^ binds tighter than a sign)."""
    v = float(v)
    if not _math.isfinite(v):
        raise ValueError(f"cdp.sdf: a number in the model is not finite ({v!r})")
    if v == 0:
        return "0"
    return repr(v) if v > 0 else f"({v!r})"


def _enclosed(s):
    """Whether s is one group: '(...)' or 'name(...)' with the first '(' closed at the end."""
    i = s.find("(")
    if i < 0 or not s.endswith(")") or (i > 0 and not _NAME.match(s[:i])):
        return False
    depth = 0
    for j in range(i, len(s)):
        if s[j] == "(":
            depth += 1
        elif s[j] == ")":
            depth -= 1
            if depth == 0:
                return j == len(s) - 1
    return False


def _is_atom(s):
    return bool(_NAME.match(s) or _NUMBER.match(s) or _enclosed(s))


def _is_cheap(s):
    """A name or a number: nothing to gain by naming it."""
    return bool(_NAME.match(s) or _NUMBER.match(s))


def _par(s):
    """s as an operand of any operator."""
    return s if _is_atom(s) else f"({s})"


def _neg(s):
    return f"-{_par(s)}"


def _lin(coefficients, p, offset=0.0):
    """sum c_j p_j + offset as text, zero terms left out."""
    terms = []
    for c, v in zip(coefficients, p):
        if c == 0:
            continue
        mag = abs(c)
        t = v if mag == 1.0 else f"{_num(mag)}*{_par(v)}"
        terms.append(("-" if c < 0 else "+", t))
    if offset != 0 or not terms:
        terms.append(("-" if offset < 0 else "+", _num(abs(offset))))
    sign, first = terms[0]
    text = first if sign == "+" else f"-{_par(first)}"
    for sign, t in terms[1:]:
        text += f" {sign} {t}"
    return text


class _Renderer:
    """Renders a tree to (formula, definitions). Run twice: the first pass counts how often each
    (node, coordinates) pair is reached, the second names those reached more than once (names
    other than those of shared values come out the same in both passes; where they do not, a
    value is only left unnamed). A formula defined twice gets one name."""

    def __init__(self, counts=None):
        self.counting = counts is None
        self.counts = {} if counts is None else counts
        self.memo = {}
        self.define = {}
        self.serial = {}
        self.by_text = {}

    def fresh(self, prefix, formula):
        """A name for formula: the one it already has, else a new one (_<prefix><n>)."""
        if formula in self.by_text:
            return self.by_text[formula]
        n = self.serial.get(prefix, 0)
        self.serial[prefix] = n + 1
        name = f"_{prefix}{n}"
        self.define[name] = formula
        self.by_text[formula] = name
        return name

    def named(self, prefix, formula):
        """formula as something cheap to repeat: itself if a name or a number, else a new name."""
        return formula if _is_cheap(formula) else self.fresh(prefix, formula)

    def render(self, node, p):
        key = (id(node), p)
        if key in self.memo:
            if self.counting:
                self.counts[key] += 1
            return self.memo[key]
        text = node._render(self, p)
        if self.counting:
            self.counts[key] = 1
        elif self.counts.get(key, 1) > 1:
            text = self.named("s", text)
        self.memo[key] = text
        return text

    def coordinates(self, rows, offset, p):
        """The coordinates m p + offset, each as an atom: plain sums of one input coordinate
        that is a plain name stay inline, others are named."""
        out = []
        for row, t in zip(rows, offset):
            used = [j for j in range(3) if row[j] != 0]
            text = _lin(row, p, t)
            if not used:
                out.append(_par(text))  # a constant
            elif len(used) == 1 and row[used[0]] == 1.0 and t == 0:
                out.append(p[used[0]])  # the input coordinate itself
            elif len(used) == 1 and _NAME.match(p[used[0]]):
                out.append(f"({text})")  # a x + b of a name: cheaper inline than named
            else:
                out.append(self.fresh("p", text))
        return tuple(out)


def _render_tree(root):
    counting = _Renderer()
    counting.render(root, ("x", "y", "z"))
    naming = _Renderer(counting.counts)
    formula = naming.render(root, ("x", "y", "z"))
    return formula, naming.define


# ---------------------------------------------------------------------------------------------
# The node.

class SDF:
    """A 3D signed distance model: an immutable node of a tree that renders to an `expression`
    field. Build one with the primitives (sphere, box, ...) and combine with | (union),
    & (intersection), - (difference) and the methods (translate, rotate, union(..., k=), ...).
    """

    __slots__ = ("_render_fn", "_box", "_k", "_desc", "_affine", "_children", "_cache")

    def __init__(self, render, box, desc, children=(), affine=None):
        init = object.__setattr__
        init(self, "_render_fn", render)
        init(self, "_box", (tuple(float(v) for v in box[0]), tuple(float(v) for v in box[1])))
        init(self, "_k", None)
        init(self, "_desc", desc)
        init(self, "_children", tuple(children))  # kept alive for the id()s of the renderer's memo
        init(self, "_affine", affine)  # (child, m, t, s, m_inv, t_inv) of a pure affine transform
        init(self, "_cache", None)  # the compiled field of __call__

    def __setattr__(self, name, value):
        raise AttributeError("cdp.sdf.SDF is immutable: operations return new models")

    def _render(self, r, p):
        return self._render_fn(r, p)

    # -- what it renders to -------------------------------------------------------------------

    @property
    def bounds(self):
        """The conservative box ((xmin, ymin, zmin), (xmax, ymax, zmax)) of the inside; sides may
        be infinite."""
        return self._box

    def formula(self):
        """(formula, definitions): the expression's "value" and "define"."""
        return _render_tree(self)

    def _field_bounds(self, bounds, pad):
        if bounds is not None:
            lo, hi = _vec3(bounds[0], "bounds[0]"), _vec3(bounds[1], "bounds[1]")
            if any(a >= b for a, b in zip(lo, hi)):
                raise ValueError(f"bounds: min {lo} must be below max {hi} on every axis")
            return lo, hi
        box = self._box
        if not _box_is_finite(box):
            raise ValueError(
                f"cdp.sdf: the model is unbounded (its box is {_box_text(box)}): intersect it with a bounded "
                "shape or give bounds=((xmin, ymin, zmin), (xmax, ymax, zmax))")
        if _box_is_empty(box):
            raise ValueError(f"cdp.sdf: the model's box is empty ({_box_text(box)}): it has no inside")
        pad = _scalar(pad, "pad")
        if pad < 0:
            raise ValueError(f"pad: must not be negative, found {pad!r}")
        margin = pad * max(h - l for l, h in zip(*box))
        if margin == 0:
            margin = pad or 1e-9
        return tuple(v - margin for v in box[0]), tuple(v + margin for v in box[1])

    def to_json(self, bounds=None, pad=0.1):
        """The field file's dict: {"type": "expression", "value": ..., "define": {...}, "bounds":
        [[...], [...]]} ("define" left out when empty). bounds: the box given to the field, used as
        is (default None: the model's box, padded by pad, default 0.1, times its longest side on
        every side)."""
        lo, hi = self._field_bounds(bounds, pad)
        formula, define = self.formula()
        spec = {"type": "expression", "value": formula}
        if define:
            spec["define"] = define
        spec["bounds"] = [list(lo), list(hi)]
        return spec

    def save(self, path, bounds=None, pad=0.1):
        """Writes to_json(bounds, pad) as a field file at path (build/bin/polygonize FILE -o OUT.ply);
        bounds (default None) and pad (default 0.1) as in to_json."""
        spec = self.to_json(bounds, pad)
        with open(_os.fspath(path), "w", encoding="utf-8") as f:
            _json.dump(spec, f, indent=2)
            f.write("\n")

    def field(self, bounds=None, pad=0.1):
        """A cdp.Field (an expression with exact derivatives) of the model; bounds (default None)
        and pad (default 0.1) as in to_json."""
        spec = self.to_json(bounds, pad)
        return _cdp.expression(spec["value"], spec["bounds"], define=spec.get("define"))

    def __call__(self, points):
        """F at the rows of an (N, 3) array, as a numpy array (through the compiled field)."""
        if self._cache is None:
            bounds = None if _box_is_finite(self._box) and not _box_is_empty(self._box) else ((-1, -1, -1), (1, 1, 1))
            object.__setattr__(self, "_cache", self.field(bounds))
        return self._cache.values(points)

    def __repr__(self):
        desc = self._desc if len(self._desc) <= 200 else self._desc[:197] + "..."
        return f"<cdp.sdf.SDF {desc}>"

    # -- operators ----------------------------------------------------------------------------

    def k(self, k=None):
        """A copy that smooths the operation it is the right operand of with radius k
        (a | b.k(0.1) is union(a, b, k=0.1))."""
        other = _copy.copy(self)
        object.__setattr__(other, "_k", None if k is None else _positive(k, "k"))
        return other

    def __copy__(self):
        other = object.__new__(SDF)
        for name in SDF.__slots__:
            object.__setattr__(other, name, getattr(self, name) if name != "_cache" else None)
        return other

    def __or__(self, other):
        return union(self, other)

    def __and__(self, other):
        return intersection(self, other)

    def __sub__(self, other):
        return difference(self, other)

    def __neg__(self):
        return negate(self)

    def union(self, *others, k=None):
        """union(self, *others, k=None): min, or the smooth min of radius k (default None: sharp)."""
        return union(self, *others, k=k)

    def intersection(self, *others, k=None):
        """intersection(self, *others, k=None): max, or the smooth max of radius k (default None: sharp)."""
        return intersection(self, *others, k=k)

    def difference(self, *others, k=None):
        """difference(self, *others, k=None): max(self, -other, ...), or smooth with radius k (default
        None: sharp)."""
        return difference(self, *others, k=k)

    def blend(self, *others, k=0.5):
        """blend(self, *others, k=0.5): (1 - k) self + k other, folded from the left."""
        return blend(self, *others, k=k)

    def negate(self):
        """negate(self): -F, inside and outside swapped."""
        return negate(self)

    def shell(self, thickness):
        """shell(self, thickness): |F| - thickness/2."""
        return shell(self, thickness)

    def dilate(self, r):
        """dilate(self, r): F - r, grown by r."""
        return dilate(self, r)

    def erode(self, r):
        """erode(self, r): F + r, shrunk by r."""
        return erode(self, r)

    def translate(self, offset):
        """translate(self, offset): the model moved by offset."""
        return translate(self, offset)

    def scale(self, factor):
        """scale(self, factor): the model scaled about the origin (see cdp.sdf.scale)."""
        return scale(self, factor)

    def rotate(self, angle, vector=Z):
        """rotate(self, angle, vector=Z): turned by angle (radians) about vector (default Z)."""
        return rotate(self, angle, vector)

    def orient(self, axis):
        """orient(self, axis): turned so that its +Z axis points along axis."""
        return orient(self, axis)

    def repeat(self, spacing, count=None, padding=0):
        """repeat(self, spacing, count=None, padding=0): copies every spacing, count (default None:
        infinitely many) on each side, padding 0 or 1 (see cdp.sdf.repeat)."""
        return repeat(self, spacing, count, padding)

    def twist(self, k):
        """twist(self, k): twisted about Z by k radians per unit of z."""
        return twist(self, k)

    def bend(self, k):
        """bend(self, k): bent in the XY plane, (x, y) turned by k x radians."""
        return bend(self, k)


def _box_text(b):
    return "(" + ", ".join("(" + ", ".join(repr(v) for v in c) + ")" for c in b) + ")"


def _check(node, what):
    if not isinstance(node, SDF):
        raise TypeError(f"{what}: expected a cdp.sdf.SDF, found {type(node).__name__}")
    return node


def _fmt(*values):
    return ", ".join(repr(v) if not isinstance(v, tuple) else "(" + ", ".join(repr(c) for c in v) + ")"
                     for v in values)


# ---------------------------------------------------------------------------------------------
# Primitives (centered at the origin; centers and axes through affine transforms).

def _at(node, center):
    return node if center == ORIGIN else translate(node, center)


def sphere(radius=1, center=ORIGIN):
    """The exact distance to a sphere of the given radius (default 1) around center (default
    ORIGIN)."""
    r = _positive(radius, "sphere: radius")
    c = _vec3(center, "sphere: center")
    node = SDF(lambda R, p: f"hypot({p[0]}, {p[1]}, {p[2]}) - {_num(r)}", ((-r,) * 3, (r,) * 3),
               f"sphere({_fmt(r)})")
    return _at(node, c)


def box(size=1, center=ORIGIN, a=None, b=None):
    """A box of side lengths size (one number or three; default 1) around center (default ORIGIN),
    or with corners a and b (default None; both or neither, in place of size and center):
    max(|x| - sx/2, |y| - sy/2, |z| - sz/2). Sharp edges (creases for the mesher); exact inside
    and where the nearest point is on a face, a lower bound near edges and corners outside."""
    if a is not None or b is not None:
        if a is None or b is None:
            raise ValueError("box: give both corners a and b, or neither")
        a, b = _vec3(a, "box: a"), _vec3(b, "box: b")
        size = tuple(abs(q - p) for p, q in zip(a, b))
        center = tuple((p + q) / 2 for p, q in zip(a, b))
    s = _vec3(size, "box: size", allow_scalar=True)
    if min(s) <= 0:
        raise ValueError(f"box: size must be positive, found {s}")
    c = _vec3(center, "box: center")
    h = tuple(v / 2 for v in s)
    node = SDF(lambda R, p: "max(" + ", ".join(f"abs({p[i]}) - {_num(h[i])}" for i in range(3)) + ")",
               (tuple(-v for v in h), h), f"box({_fmt(s)})")
    return _at(node, c)


def _rounded_corner(R, d):
    """Exact distance from the components d (atoms) of |p| - half size: length(max(d, 0)) +
    min(max(d), 0), written without sqrt(0) inside: hypot(max(d, 0), min(m, 0)) + 2 min(m, 0)."""
    m = R.named("m", "min(max(" + ", ".join(d) + "), 0)") if len(d) > 1 else R.named("m", f"min({d[0]}, 0)")
    return "hypot(" + ", ".join(f"max({v}, 0)" for v in d) + f", {m}) + 2*{m}"


def rounded_box(size, radius, center=ORIGIN):
    """Inigo Quilez's exact rounded box: the box of side lengths size with edges and corners
    rounded by radius (size includes the rounding), around center (default ORIGIN)."""
    s = _vec3(size, "rounded_box: size", allow_scalar=True)
    r = _scalar(radius, "rounded_box: radius")
    if r < 0 or any(2 * r > v for v in s):
        raise ValueError(f"rounded_box: radius must be in [0, min(size)/2], found {r!r} for size {s}")
    c = _vec3(center, "rounded_box: center")
    h = tuple(v / 2 for v in s)

    def render(R, p):
        q = [R.named("q", f"abs({p[i]}) - {_num(h[i] - r)}") for i in range(3)]
        return f"{_rounded_corner(R, q)} - {_num(r)}"

    return _at(SDF(render, (tuple(-v for v in h), h), f"rounded_box({_fmt(s, r)})"), c)


def torus(r1, r2):
    """The exact distance to a torus around Z: ring radius r1, tube radius r2."""
    r1 = _positive(r1, "torus: r1")
    r2 = _positive(r2, "torus: r2")
    e = r1 + r2
    return SDF(lambda R, p: f"hypot(hypot({p[0]}, {p[1]}) - {_num(r1)}, {p[2]}) - {_num(r2)}",
               ((-e, -e, -r2), (e, e, r2)), f"torus({_fmt(r1, r2)})")


def _along(node, a, b, what):
    """node (built along Z, centered at the origin) turned onto the segment a-b, centered at
    its midpoint."""
    axis = _sub(b, a)
    if _norm(axis) == 0:
        raise ValueError(f"{what}: a and b must differ")
    mid = tuple((p + q) / 2 for p, q in zip(a, b))
    return _at(orient(node, axis), mid)


def capsule(a, b, radius):
    """The exact distance to the segment a-b, minus radius."""
    a, b = _vec3(a, "capsule: a"), _vec3(b, "capsule: b")
    r = _positive(radius, "capsule: radius")
    h = _norm(_sub(b, a)) / 2
    node = SDF(lambda R, p: (f"hypot({p[0]}, {p[1]}, {p[2]} - clamp({p[2]}, {_num(-h)}, {_num(h)})) - {_num(r)}"),
               ((-r, -r, -h - r), (r, r, h + r)), f"capsule(h={_fmt(h, r)})")
    return _along(node, a, b, "capsule")


def cylinder(radius):
    """An infinite cylinder around Z (exact distance); bound it by an intersection or bounds=."""
    r = _positive(radius, "cylinder: radius")
    return SDF(lambda R, p: f"hypot({p[0]}, {p[1]}) - {_num(r)}", ((-r, -r, -_INF), (r, r, _INF)),
               f"cylinder({_fmt(r)})")


def capped_cylinder(a, b, radius):
    """The cylinder of the given radius from a to b, with sharp rims:
    max(|p - axis| - radius, |t| - length/2). Exact where the nearest point is on the side or a
    cap, and inside; a lower bound near the rims outside."""
    a, b = _vec3(a, "capped_cylinder: a"), _vec3(b, "capped_cylinder: b")
    r = _positive(radius, "capped_cylinder: radius")
    h = _norm(_sub(b, a)) / 2
    node = SDF(lambda R, p: f"max(hypot({p[0]}, {p[1]}) - {_num(r)}, abs({p[2]}) - {_num(h)})",
               ((-r, -r, -h), (r, r, h)), f"capped_cylinder({_fmt(h, r)})")
    return _along(node, a, b, "capped_cylinder")


def rounded_cylinder(ra, rb, h):
    """Inigo Quilez's exact rounded cylinder around Z, as fogleman/sdf: radius ra, edge radius rb,
    height h (centered at the origin; both include the rounding)."""
    ra = _positive(ra, "rounded_cylinder: ra")
    rb = _scalar(rb, "rounded_cylinder: rb")
    h = _positive(h, "rounded_cylinder: h")
    if rb < 0 or rb > ra or 2 * rb > h:
        raise ValueError(f"rounded_cylinder: rb must be in [0, min(ra, h/2)], found {rb!r}")

    def render(R, p):
        d = [R.named("q", f"hypot({p[0]}, {p[1]}) - {_num(ra - rb)}"),
             R.named("q", f"abs({p[2]}) - {_num(h / 2 - rb)}")]
        return f"{_rounded_corner(R, d)} - {_num(rb)}"

    return SDF(render, ((-ra, -ra, -h / 2), (ra, ra, h / 2)), f"rounded_cylinder({_fmt(ra, rb, h)})")


def capped_cone(a, b, ra, rb):
    """The cone from a (radius ra) to b (radius rb), with sharp rims: the max of the distance to
    the infinite cone's side and |t| - length/2 (exact where the nearest point is on the side or
    a cap, and inside; a lower bound near the rims outside)."""
    a, b = _vec3(a, "capped_cone: a"), _vec3(b, "capped_cone: b")
    ra = _scalar(ra, "capped_cone: ra")
    rb = _scalar(rb, "capped_cone: rb")
    if ra < 0 or rb < 0 or ra + rb == 0:
        raise ValueError(f"capped_cone: radii must be non-negative and not both 0, found {ra!r}, {rb!r}")
    h = _norm(_sub(b, a)) / 2
    if h == 0:
        raise ValueError("capped_cone: a and b must differ")
    # radius at height t: (ra + rb)/2 + (rb - ra) t / (2h); side distance (rho - radius(t)) cos(alpha)
    slope = (rb - ra) / (2 * h)
    cos = 1 / _math.sqrt(1 + slope * slope)
    mid = (ra + rb) / 2
    big = max(ra, rb)

    def render(R, p):
        side = f"{_num(cos)}*(hypot({p[0]}, {p[1]}) - {_par(_lin((0, 0, slope), p, mid))})"
        return f"max({side}, abs({p[2]}) - {_num(h)})"

    node = SDF(render, ((-big, -big, -h), (big, big, h)), f"capped_cone({_fmt(h, ra, rb)})")
    return _along(node, a, b, "capped_cone")


def plane(normal=UP, point=ORIGIN):
    """The half-space on the side `normal` (default UP) points to, its boundary through point
    (default ORIGIN), as in fogleman/sdf: F = (point - p) . n, the exact signed distance.
    Unbounded."""
    n = _normalize(_vec3(normal, "plane: normal"), "plane: normal")
    q = _vec3(point, "plane: point")
    lo, hi = [-_INF] * 3, [_INF] * 3
    nz = [i for i in range(3) if n[i] != 0]
    if len(nz) == 1:  # an axis-aligned half-space bounds one side
        i = nz[0]
        if n[i] > 0:
            lo[i] = q[i]
        else:
            hi[i] = q[i]
    c = _dot(n, q)
    return SDF(lambda R, p: _lin(tuple(-v for v in n), p, c), (tuple(lo), tuple(hi)), f"plane({_fmt(n, q)})")


def slab(x0=None, y0=None, z0=None, x1=None, y1=None, z1=None, k=None):
    """x0 <= x <= x1, y0 <= y <= y1, z0 <= z <= z1 for the bounds given (None: open), the max of
    the half-spaces (exact inside, a bound near edges outside); k smooths the intersection."""
    given = {"x0": x0, "y0": y0, "z0": z0, "x1": x1, "y1": y1, "z1": z1}
    halves = []
    for name, v in given.items():
        if v is None:
            continue
        v = _scalar(v, f"slab: {name}")
        i = "xyz".index(name[0])
        normal = tuple((1.0 if name[1] == "0" else -1.0) if j == i else 0.0 for j in range(3))
        halves.append(plane(normal, tuple(v if j == i else 0.0 for j in range(3))))
    if not halves:
        raise ValueError("slab: give at least one of x0, y0, z0, x1, y1, z1")
    if len(halves) == 1:
        return halves[0]
    return intersection(*halves, k=k)


def ellipsoid(size):
    """Inigo Quilez's ellipsoid bound with radii size: k0 (k0 - 1) / k1, k0 = |p / r|,
    k1 = |p / r^2| (the surface exact, the value close to the distance near it)."""
    r = _vec3(size, "ellipsoid: size", allow_scalar=True)
    if min(r) <= 0:
        raise ValueError(f"ellipsoid: size must be positive, found {r}")

    def render(R, p):
        k0 = R.named("e", "hypot(" + ", ".join(f"{p[i]}/{_num(r[i])}" for i in range(3)) + ")")
        k1 = "hypot(" + ", ".join(f"{p[i]}/{_num(r[i] * r[i])}" for i in range(3)) + ")"
        return f"{k0}*({k0} - 1)/{k1}"

    return SDF(render, (tuple(-v for v in r), r), f"ellipsoid({_fmt(r)})")


def octahedron(r):
    """The regular octahedron |x| + |y| + |z| <= r: (|x| + |y| + |z| - r) / sqrt(3), exact
    where the nearest point is on a face."""
    r = _positive(r, "octahedron: r")
    return SDF(lambda R, p: f"(abs({p[0]}) + abs({p[1]}) + abs({p[2]}) - {_num(r)})*{_num(1 / _math.sqrt(3))}",
               ((-r,) * 3, (r,) * 3), f"octahedron({_fmt(r)})")


def tetrahedron(r):
    """The regular tetrahedron with vertices (r, r, r), (-r, -r, r), (r, -r, -r), (-r, r, -r),
    as fogleman/sdf: (max(|x + y| - z, |x - y| + z) - r) / sqrt(3)."""
    r = _positive(r, "tetrahedron: r")
    return SDF(lambda R, p: (f"(max(abs({p[0]} + {p[1]}) - {p[2]}, abs({p[0]} - {p[1]}) + {p[2]}) - {_num(r)})"
                             f"*{_num(1 / _math.sqrt(3))}"),
               ((-r,) * 3, (r,) * 3), f"tetrahedron({_fmt(r)})")


# ---------------------------------------------------------------------------------------------
# Operations.

def _fold(kind, a, others, k):
    """The pairwise left fold of fogleman/sdf's union, intersection, difference: sharp steps
    gathered into one n-ary min/max, each smooth step Quilez's polynomial form."""
    a = _check(a, kind)
    others = [_check(o, kind) for o in others]
    if not others:
        return a
    if k is not None:
        k = _positive(k, f"{kind}: k")
    ks = [k if k is not None else o._k for o in others]
    # Flatten: a sharp or smooth fold of the same kind on the left continues it.
    if isinstance(a._render_fn, _Fold) and a._render_fn.kind == kind:
        operands = list(a._render_fn.operands) + others
        ks = list(a._render_fn.ks) + ks
    else:
        operands = [a] + others
        ks = [None] + ks
    box = operands[0]._box
    for o, kk in zip(operands[1:], ks[1:]):
        if kind == "union":
            box = _box_union(box, o._box)
            if kk is not None:
                box = _box_inflate(box, kk)
        elif kind == "intersection":
            box = _box_intersection(box, o._box)
    fn = _Fold(kind, operands, ks)
    desc = f"{kind}(" + ", ".join(o._desc for o in operands) + (
        "" if all(v is None for v in ks) else ", k=" + repr([v for v in ks[1:]])) + ")"
    return SDF(fn, box, desc, operands)


class _Fold:
    def __init__(self, kind, operands, ks):
        self.kind, self.operands, self.ks = kind, tuple(operands), tuple(ks)

    def __call__(self, R, p):
        sharp = "min" if self.kind == "union" else "max"
        d1 = R.render(self.operands[0], p)
        pending = [d1]  # terms of a sharp min/max not yet closed
        for o, k in zip(self.operands[1:], self.ks[1:]):
            d2 = R.render(o, p)
            if k is None:
                pending.append(_neg(d2) if self.kind == "difference" else d2)
                continue
            d1 = pending[0] if len(pending) == 1 else f"{sharp}({', '.join(pending)})"
            a = R.named("d", d1)
            b = R.named("d", d2)
            K = _num(k)
            c = _num(0.5 / k)
            if self.kind == "union":
                h = R.named("h", f"clamp(0.5 + ({b} - {a})*{c}, 0, 1)")
                d1 = f"{b} + ({a} - {b})*{h} - {K}*{h}*(1 - {h})"
            elif self.kind == "intersection":
                h = R.named("h", f"clamp(0.5 - ({b} - {a})*{c}, 0, 1)")
                d1 = f"{b} + ({a} - {b})*{h} + {K}*{h}*(1 - {h})"
            else:
                h = R.named("h", f"clamp(0.5 - ({b} + {a})*{c}, 0, 1)")
                d1 = f"{a} - ({b} + {a})*{h} + {K}*{h}*(1 - {h})"
            pending = [d1]
        return pending[0] if len(pending) == 1 else f"{sharp}({', '.join(pending)})"


def union(a, *bs, k=None):
    """min(a, b, ...), or with k (or b.k(...)) Quilez's polynomial smooth min of radius k,
    folded from the left."""
    return _fold("union", a, bs, k)


def intersection(a, *bs, k=None):
    """max(a, b, ...), or the smooth max of radius k."""
    return _fold("intersection", a, bs, k)


def difference(a, *bs, k=None):
    """max(a, -b, ...), or the smooth difference of radius k."""
    return _fold("difference", a, bs, k)


def blend(a, *bs, k=0.5):
    """The linear interpolation (1 - k) a + k b with k (default 0.5), folded from the left over
    bs (fogleman/sdf's blend)."""
    a = _check(a, "blend")
    k = _scalar(k, "blend: k")
    node = a
    for b in bs:
        b = _check(b, "blend")
        left = node

        def render(R, p, left=left, b=b):
            return f"{_num(1 - k)}*{_par(R.render(left, p))} + {_num(k)}*{_par(R.render(b, p))}"

        node = SDF(render, _box_union(left._box, b._box), f"blend({left._desc}, {b._desc}, k={k!r})", (left, b))
    return node


def negate(other):
    """-F: inside and outside swapped (an unbounded model)."""
    other = _check(other, "negate")
    return SDF(lambda R, p: _neg(R.render(other, p)), _UNBOUNDED, f"negate({other._desc})", (other,))


def shell(other, thickness):
    """|F| - thickness/2: a shell of that thickness around the surface."""
    other = _check(other, "shell")
    t = _positive(thickness, "shell: thickness")
    return SDF(lambda R, p: f"abs({R.render(other, p)}) - {_num(t / 2)}", _box_inflate(other._box, t / 2),
               f"shell({other._desc}, {t!r})", (other,))


def dilate(other, r):
    """F - r: grown by r."""
    other = _check(other, "dilate")
    r = _scalar(r, "dilate: r")
    return SDF(lambda R, p: f"{R.render(other, p)} - {_num(r)}", _box_inflate(other._box, max(r, 0.0)),
               f"dilate({other._desc}, {r!r})", (other,))


def erode(other, r):
    """F + r: shrunk by r (the box is kept)."""
    other = _check(other, "erode")
    r = _scalar(r, "erode: r")
    return SDF(lambda R, p: f"{R.render(other, p)} + {_num(r)}", _box_inflate(other._box, max(-r, 0.0)),
               f"erode({other._desc}, {r!r})", (other,))


# Affine transforms: the child is evaluated at m p + t and its value multiplied by s; the child's
# box maps to the world through p = m_inv c + t_inv. A transform of a transform is one transform.

def _affine(other, m, t, s, m_inv, t_inv, name, args):
    other = _check(other, name)
    if other._affine is not None:
        child, m2, t2, s2, mi2, ti2 = other._affine
        # child at m2 (m p + t) + t2, value s s2; world p = m_inv (mi2 c + ti2) + t_inv
        m, t = _snap(_matmul(m2, m)), tuple(a + b for a, b in zip(_matvec(m2, t), t2))
        m_inv, t_inv = _snap(_matmul(m_inv, mi2)), tuple(a + b for a, b in zip(_matvec(m_inv, ti2), t_inv))
        s = s * s2
        desc = f"{name}({other._desc}, {args})"
        other = child
    else:
        desc = f"{name}({other._desc}, {args})"
    if m == _IDENTITY and all(v == 0 for v in t) and s == 1:
        return other
    box = _box_affine(other._box, m_inv, t_inv)
    scale_text = None if s == 1 else _num(s)

    def render(R, p):
        c = R.coordinates(m, t, p)
        d = R.render(other, c)
        return d if scale_text is None else f"{scale_text}*{_par(d)}"

    return SDF(render, box, desc, (other,), affine=(other, m, t, s, m_inv, t_inv))


def translate(other, offset):
    """The model moved by offset."""
    o = _vec3(offset, "translate: offset")
    return _affine(other, _IDENTITY, tuple(-v for v in o), 1.0, _IDENTITY, o, "translate", _fmt(o))


def scale(other, factor):
    """The model scaled by factor about the origin: one number (exact: F(p / s) s) or three
    (F(p / s) min(s): a bound on the distance, not the distance). Factors must be positive."""
    f = _vec3(factor, "scale: factor", allow_scalar=True)
    if min(f) <= 0:
        raise ValueError(f"scale: factors must be positive, found {f}")
    m = ((1 / f[0], 0.0, 0.0), (0.0, 1 / f[1], 0.0), (0.0, 0.0, 1 / f[2]))
    m_inv = ((f[0], 0.0, 0.0), (0.0, f[1], 0.0), (0.0, 0.0, f[2]))
    return _affine(other, m, ORIGIN, min(f), m_inv, ORIGIN, "scale", _fmt(f))


def rotate(other, angle, vector=Z):
    """The model turned by angle (radians) about vector (default Z) through the origin
    (right-hand rule)."""
    a = _scalar(angle, "rotate: angle")
    v = _normalize(_vec3(vector, "rotate: vector"), "rotate: vector")
    r = _rotation(a, v)
    return _affine(other, _transpose(r), ORIGIN, 1.0, r, ORIGIN, "rotate", _fmt(a, v))


def orient(other, axis):
    """The model turned so that its +Z axis points along axis (Z -> X: cylinder(r).orient(X)
    lies along X)."""
    v = _normalize(_vec3(axis, "orient: axis"), "orient: axis")
    r = _rotation_z_to(v)
    return _affine(other, _transpose(r), ORIGIN, 1.0, r, ORIGIN, "orient", _fmt(v))


# Non-affine transforms: their coordinates are named definitions.

_MAX_EXPLICIT_COPIES = 125


def repeat(other, spacing, count=None, padding=0):
    """Copies of the model every spacing (one number or three; 0: no repetition on that axis),
    infinitely many or count (one number or three) on each side of the original.

    padding=0: p - s clamp(round(p / s), -count, count), one evaluation of the model; each copy
    must stay inside its cell (|p| < s/2 around it), where round does not jump.
    padding=1 with count: the union (min) of the translated copies, no round at all: copies
    may overlap, and meet in creases the mesher follows (more than 125 copies: as without
    count, clamped to it).
    padding=1 without count: the min over the copy of the cell and its neighbours (3 copies of
    the model per repeated axis), continuous where a copy reaches into the next cell; where two
    copies meet exactly on a cell edge, the jump of round is there too and the mesher may fail."""
    other = _check(other, "repeat")
    s = _vec3(spacing, "repeat: spacing", allow_scalar=True)
    if min(s) < 0:
        raise ValueError(f"repeat: spacing must not be negative, found {s}")
    c = None if count is None else _vec3(count, "repeat: count", allow_scalar=True)
    if c is not None and (min(c) < 0 or any(v != int(v) for v in c)):
        raise ValueError(f"repeat: count must be whole numbers >= 0, found {c}")
    if padding not in (0, 1):
        raise ValueError(f"repeat: padding must be 0 or 1, found {padding!r}")
    axes = [i for i in range(3) if s[i] != 0 and (c is None or c[i] > 0)]
    if not axes:
        return other
    if c is not None and padding:
        # Finitely many copies that may meet: their union, without steps at all (where copies
        # meet is a crease of a min, which the mesher follows, and not a jump of round).
        combos = [()]
        for i in axes:
            combos = [cb + (n,) for cb in combos for n in range(-int(c[i]), int(c[i]) + 1)]
        if len(combos) <= _MAX_EXPLICIT_COPIES:
            copies = []
            for cb in combos:
                offset = [0.0, 0.0, 0.0]
                for i, n in zip(axes, cb):
                    offset[i] = s[i] * n
                copies.append(translate(other, offset))
            return union(*copies)
    lo, hi = list(other._box[0]), list(other._box[1])
    for i in axes:
        reach = _INF if c is None else s[i] * c[i]
        lo[i] -= reach
        hi[i] += reach

    def render(R, p):
        # index on each repeated axis, then the coordinates of each neighbour offset
        offsets = (0,) if padding == 0 else (0, -1, 1)
        coords = {}
        for i in axes:
            index = f"round({p[i]}/{_num(s[i])})"
            if padding:
                index = R.named("r", index)
            for n in offsets:
                idx = index if n == 0 else f"{index} + {n}" if n > 0 else f"{index} - {-n}"
                if c is not None:
                    idx = f"clamp({idx}, {_num(-c[i])}, {_num(c[i])})"
                coords[i, n] = R.fresh("p", f"{p[i]} - {_num(s[i])}*{_par(idx)}")
        values = []
        combos = [()]
        for i in axes:
            combos = [cb + (n,) for cb in combos for n in offsets]
        for cb in combos:
            q = list(p)
            for i, n in zip(axes, cb):
                q[i] = coords[i, n]
            values.append(R.render(other, tuple(q)))
        return values[0] if len(values) == 1 else "min(" + ", ".join(values) + ")"

    return SDF(render, (tuple(lo), tuple(hi)), f"repeat({other._desc}, {_fmt(s)}, count={c!r}, padding={padding})",
               (other,))


def _turn_xy(other, k, along, name):
    """The model with (x, y) turned by k radians per unit of coordinate `along` (twist: z, bend: x)."""
    other = _check(other, name)
    k = _scalar(k, name + ": k")

    def render(R, p):
        a = R.named("a", _lin((k,), (p[along],)))
        cs, sn = R.named("c", f"cos({a})"), R.named("c", f"sin({a})")
        q = (R.fresh("p", f"{cs}*{p[0]} - {sn}*{p[1]}"), R.fresh("p", f"{sn}*{p[0]} + {cs}*{p[1]}"), p[2])
        return R.render(other, q)

    return SDF(render, _box_radial(other._box, (0, 1)), f"{name}({other._desc}, {k!r})", (other,))


def twist(other, k):
    """The model twisted about Z by k radians per unit of z (not distance-preserving)."""
    return _turn_xy(other, k, 2, "twist")


def bend(other, k):
    """The model bent in the XY plane: (x, y) turned by k x radians, as fogleman/sdf (not
    distance-preserving)."""
    return _turn_xy(other, k, 0, "bend")
