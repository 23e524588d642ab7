"""The type stubs (python/cdp/_cdp.pyi, __init__.pyi) against the package, so that they cannot
drift: every public name of cdp._cdp and of cdp is declared, nothing is declared that the
package lacks, and every function's and method's parameters (names, kinds, defaults) are the
runtime's. The compiled functions' runtime signatures are the first lines of their docstrings
(pybind11 writes them from the bindings); the meshing functions' **options are the rows of
cdp.polygonize_options() for their method, each declared with its type (a choice as a Literal of
its choices) and None or the table's default. Also: cdp.__version__ is the project's version, and
every keyword of the public functions is named in its docstring."""
import ast
import inspect
import pathlib
import re
import types

import pytest

import cdp
from cdp import _cdp

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUBS = ROOT / "python" / "cdp"
NO_DEFAULT = "<required>"
# The meshing functions whose **options are the options table's rows for a method.
OPTION_METHODS = {"polygonize": None, "marching_cubes": "mc", "marching_tetrahedra": "mt"}
# Keywords they still take through **options though the table has no row for them.
DEPRECATED_KEYWORDS = {"return_normals"}
# Keywords the package's functions take beyond the compiled ones' (cdp.polygonize's client: the
# blocks on a Dask cluster, python/cdp/distributed.py).
PACKAGE_KEYWORDS = {"client"}


class Stub:
    """The top-level declarations of a .pyi file: functions (a list: overloads), classes, annotated
    names, names re-exported with `import X as X`, and modules imported with `*`."""

    def __init__(self, path):
        self.path = path
        self.defs = {}
        self.reexports = set()
        self.star = []
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                self.defs.setdefault(node.name, []).append(node)
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                self.defs.setdefault(node.target.id, []).append(node)
            elif isinstance(node, ast.ImportFrom):
                for alias in node.names:
                    if alias.name == "*":
                        self.star.append(node.module)
                    elif alias.asname == alias.name:
                        self.reexports.add(alias.name)
            elif isinstance(node, ast.Import):
                self.reexports.update(a.name for a in node.names if a.asname == a.name)

    def public(self):
        return {n for n in self.defs if not n.startswith("_")} | self.reexports


CDP_STUB = Stub(STUBS / "_cdp.pyi")
INIT_STUB = Stub(STUBS / "__init__.pyi")


def parameters(function_def, drop_self=False):
    """[(name, kind, default, annotation text)] of an ast function definition; kind is
    positional, keyword (keyword-only), *args or **kwargs; a default as a Python value."""
    a = function_def.args
    out = []
    positional = a.posonlyargs + a.args
    defaults = [NO_DEFAULT] * (len(positional) - len(a.defaults)) + [ast.literal_eval(d) for d in a.defaults]
    for arg, default in zip(positional, defaults):
        out.append((arg.arg, "positional", default, arg.annotation))
    if a.vararg:
        out.append((a.vararg.arg, "*args", NO_DEFAULT, None))
    for arg, default in zip(a.kwonlyargs, a.kw_defaults):
        out.append((arg.arg, "keyword", NO_DEFAULT if default is None else ast.literal_eval(default), arg.annotation))
    if a.kwarg:
        out.append((a.kwarg.arg, "**kwargs", NO_DEFAULT, None))
    if drop_self and out and out[0][0] in ("self", "cls"):
        out = out[1:]
    return [(n, k, d, None if t is None else ast.unparse(t)) for n, k, d, t in out]


KINDS = {inspect.Parameter.POSITIONAL_ONLY: "positional", inspect.Parameter.POSITIONAL_OR_KEYWORD: "positional",
         inspect.Parameter.VAR_POSITIONAL: "*args", inspect.Parameter.KEYWORD_ONLY: "keyword",
         inspect.Parameter.VAR_KEYWORD: "**kwargs"}


def runtime_parameters(name, obj, drop_self=False):
    """The runtime's parameters, as parameters() gives a stub's: from the docstring's first line
    when it is a call of `name` (pybind11's signature line, or one written by hand for a wrapper
    taking **kwargs), else from inspect (a Python function's own defaults)."""
    first = (obj.__doc__ or "").lstrip().split("\n", 1)[0]
    if first.startswith(name + "("):
        try:
            return parameters(ast.parse("def " + first + ": ...").body[0], drop_self)
        except (SyntaxError, ValueError):
            pass
    out = [(p.name, KINDS[p.kind], NO_DEFAULT if p.default is p.empty else p.default, None)
           for p in inspect.signature(obj, follow_wrapped=False).parameters.values()]
    if drop_self and out and out[0][0] in ("self", "cls"):
        out = out[1:]
    return out


def option_type(option):
    kind = option["kind"]
    if kind == "choice":
        return "Literal[" + ", ".join(repr(c) for c in option["choices"]) + "]"
    return {"number": "float", "real": "float", "integer": "int", "flag": "bool", "boolean": "bool"}[kind]


def option_default(option):
    text = option["default"]
    if text is None:
        return None
    if option["kind"] in ("number", "real"):
        return float(text)
    if option["kind"] == "integer":
        return int(text)
    if option["kind"] in ("flag", "boolean"):
        return text == "true"
    return text


def compare(where, runtime, stub_defs, option_method=False, drop_self=False):
    """Differences between a runtime function and its stub (several stubs: overloads, each of
    which must have the runtime's names and kinds; a default may be left out of an overload)."""
    problems = []
    options = []
    if option_method is not False and runtime and runtime[-1][1] == "**kwargs":
        runtime = runtime[:-1]
        options = [o for o in _cdp.polygonize_options() if option_method is None or option_method in o["methods"]]
    for stub_def in stub_defs:
        stub = parameters(stub_def, drop_self)
        explicit = {n for n, *_ in runtime}
        extra = [p for p in stub if p[0] not in explicit]
        stub = [p for p in stub if p[0] in explicit]
        if [(n, k) for n, k, *_ in stub] != [(n, k) for n, k, *_ in runtime]:
            # keyword-only parameters may come in any order
            positional = lambda ps: [(n, k) for n, k, *_ in ps if k != "keyword"]  # noqa: E731
            keyword = lambda ps: sorted(n for n, k, *_ in ps if k == "keyword")  # noqa: E731
            if positional(stub) != positional(runtime) or keyword(stub) != keyword(runtime):
                problems.append(f"{where}: parameters {[(n, k) for n, k, *_ in stub]} in the stub, "
                                f"{[(n, k) for n, k, *_ in runtime]} at runtime")
        defaults = {n: d for n, _, d, _ in runtime}
        for n, _, d, _ in stub:
            if d != defaults[n] and not (len(stub_defs) > 1 and d == NO_DEFAULT):
                problems.append(f"{where}: {n} defaults to {d!r} in the stub, {defaults[n]!r} at runtime")
        table = {o["name"]: o for o in options}
        for n, k, d, annotation in extra:
            option = table.pop(n, None)
            if option is None and options and n in DEPRECATED_KEYWORDS and k == "keyword":
                continue
            if option is None:
                problems.append(f"{where}: the stub has a parameter {n} the runtime does not")
                continue
            if k != "keyword":
                problems.append(f"{where}: option {n} must be keyword-only in the stub")
            if d is not None and d != option_default(option):
                problems.append(f"{where}: option {n} defaults to {d!r} in the stub, the table says "
                                f"None or {option_default(option)!r}")
            expected = option_type(option) + (" | None" if d is None else "")
            if annotation != expected:
                problems.append(f"{where}: option {n} is {annotation} in the stub, expected {expected}")
        problems += [f"{where}: option {n} ({o['kind']}) is missing from the stub" for n, o in table.items()]
    return problems


def compare_class(where, runtime_class, class_def):
    problems = []
    members = {}
    for node in class_def.body:
        if isinstance(node, ast.FunctionDef):
            members.setdefault(node.name, []).append(node)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            members.setdefault(node.target.id, []).append(node)
    for name, value in vars(runtime_class).items():
        pybind_init = name == "__init__" and (value.__doc__ or "").startswith("__init__(")
        if name.startswith("_") and not pybind_init:
            continue
        if name not in members:
            problems.append(f"{where}.{name} is missing from the stub")
        elif isinstance(value, property):
            if not any(isinstance(d, ast.Name) and d.id == "property"
                       for node in members[name] for d in getattr(node, "decorator_list", [])):
                problems.append(f"{where}.{name} is a property at runtime, not in the stub")
        elif callable(value):
            problems += compare(f"{where}.{name}", runtime_parameters(name, value, drop_self=True), members[name],
                                drop_self=True)
    for name in members:
        if not name.startswith("_") and not hasattr(runtime_class, name):
            problems.append(f"{where}.{name} is in the stub, not at runtime")
    return problems


def check_module_names(module, stub):
    runtime = {n for n in dir(module) if not n.startswith("_")}
    problems = [f"{module.__name__}.{n} is missing from {stub.path.name}" for n in sorted(runtime - stub.public())]
    problems += [f"{stub.path.name} declares {n}, which {module.__name__} lacks" for n in sorted(stub.public() - runtime)]
    return problems


def check_definitions(module_name, obj_of, stub):
    problems = []
    for name, nodes in sorted(stub.defs.items()):
        obj = obj_of(name)
        if name.startswith("_") or obj is None:
            continue
        where = f"{module_name}.{name}"
        if isinstance(nodes[0], ast.ClassDef):
            if not isinstance(obj, type):
                problems.append(f"{where} is a class in the stub, a {type(obj).__name__} at runtime")
            elif issubclass(obj, BaseException):
                bases = [ast.unparse(b) for b in nodes[0].bases]
                if bases != [obj.__bases__[0].__name__]:
                    problems.append(f"{where} derives from {bases} in the stub, {obj.__bases__[0].__name__} at runtime")
            elif hasattr(obj, "_fields"):  # a NamedTuple
                fields = [n.target.id for n in nodes[0].body if isinstance(n, ast.AnnAssign)]
                if fields != list(obj._fields):
                    problems.append(f"{where}: fields {fields} in the stub, {list(obj._fields)} at runtime")
            else:
                problems += compare_class(where, obj, nodes[0])
        elif isinstance(nodes[0], ast.FunctionDef):
            if not callable(obj):
                problems.append(f"{where} is a function in the stub, a {type(obj).__name__} at runtime")
            else:
                problems += compare(where, runtime_parameters(name, obj), nodes, OPTION_METHODS.get(name, False))
    return problems


def test_stub_files_are_in_the_package():
    package = pathlib.Path(cdp.__file__).parent
    for name in ("_cdp.pyi", "__init__.pyi", "py.typed"):
        assert (package / name).exists(), f"{name} is not beside {cdp.__file__} (python/CMakeLists.txt copies it)"


def test_compiled_module_matches_its_stub():
    problems = check_module_names(_cdp, CDP_STUB)
    problems += check_definitions("cdp._cdp", lambda n: getattr(_cdp, n, None), CDP_STUB)
    assert not problems, "python/cdp/_cdp.pyi and cdp._cdp differ:\n  " + "\n  ".join(problems)


def test_package_matches_its_stub():
    # The package's names: the compiled module's (declared in _cdp.pyi, which __init__.pyi
    # imports with *) and its own; the Python-defined ones must be declared in __init__.pyi.
    assert "_cdp" in INIT_STUB.star
    public = set(getattr(cdp, "__all__", [])) | {n for n in dir(cdp) if not n.startswith("_")}
    public = {n for n in public if not isinstance(getattr(cdp, n, None), types.ModuleType)}
    problems = []
    for name in sorted(public):
        declared = name in INIT_STUB.public() or name in CDP_STUB.public()
        own = getattr(cdp, name) is not getattr(_cdp, name, object())
        if not declared or (own and name not in INIT_STUB.public()):
            problems.append(f"cdp.{name} is missing from __init__.pyi")
    for name in sorted(INIT_STUB.public() - public - {"sdf"}):
        problems.append(f"__init__.pyi declares {name}, which cdp lacks")
    problems += check_definitions("cdp", lambda n: getattr(cdp, n, None), INIT_STUB)
    # The functions that also take a model have the compiled ones' parameters but the first.
    for name, nodes in INIT_STUB.defs.items():
        if name in CDP_STUB.defs and isinstance(nodes[0], ast.FunctionDef) and nodes[0].args.args[0].arg == "field":
            def comparable(function_def):
                return [p[:3] + (p[3] if i else None,) for i, p in enumerate(parameters(function_def))
                        if p[0] not in DEPRECATED_KEYWORDS | PACKAGE_KEYWORDS]
            ours, theirs = comparable(nodes[0]), comparable(CDP_STUB.defs[name][0])
            if ours != theirs:
                problems.append(f"cdp.{name}: __init__.pyi and _cdp.pyi differ beyond the field's type")
    assert not problems, "python/cdp/__init__.pyi and cdp differ:\n  " + "\n  ".join(problems)


def test_version_is_the_projects():
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    version = re.search(r"project\(\s*cdp\s+VERSION\s+([0-9][0-9.]*)", text).group(1)
    from cdp import _version
    assert _version.__version__ == version
    assert getattr(cdp, "__version__", None) == version, \
        "cdp.__version__ is missing: python/cdp/__init__.py should `from ._version import __version__`"


def public_functions():
    """(qualified name, function) of the compiled module's functions and methods and of the
    public functions and SDF methods of cdp.sdf and cdp.trace."""
    out = []
    for name in dir(_cdp):
        obj = getattr(_cdp, name)
        if name.startswith("_") or isinstance(obj, type) and issubclass(obj, BaseException):
            continue
        if isinstance(obj, type):
            out += [(f"cdp.{name}.{m}", v) for m, v in vars(obj).items() if not m.startswith("_") and callable(v)]
        elif callable(obj):
            out.append((f"cdp.{name}", obj))
    for module in (cdp.sdf, cdp.trace):
        for name in getattr(module, "__all__", dir(module)):
            obj = getattr(module, name)
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            if isinstance(obj, type):
                out += [(f"{module.__name__}.{name}.{m}", v) for m, v in vars(obj).items()
                        if not m.startswith("_") and inspect.isfunction(v)]
            elif inspect.isfunction(obj):
                out.append((f"{module.__name__}.{name}", obj))
    return out


def without_signature(name, doc):
    """The docstring after a leading `name(...)` (and ` -> type`), the signature line pybind11
    writes or one written by hand."""
    if not doc.startswith(name + "("):
        return doc
    depth = 0
    for i, c in enumerate(doc):
        depth += {"(": 1, ")": -1}.get(c, 0)
        if depth == 0 and c == ")":
            rest = doc[i + 1:]
            return rest.split("\n", 1)[1] if rest.lstrip(" ").startswith("->") and "\n" in rest else rest
    return doc


@pytest.mark.parametrize("name, function", public_functions(), ids=lambda v: v if isinstance(v, str) else "")
def test_docstring_names_every_keyword(name, function):
    # A keyword: a parameter with a default, or keyword-only. The docstring's text (beyond a
    # signature line) must name it; a default other than None must be written in it too (the
    # signature line pybind11 puts first shows the defaults of compiled functions).
    doc = inspect.getdoc(function) or ""
    short = name.rsplit(".", 1)[-1]
    body = without_signature(short, doc)
    runtime = runtime_parameters(short, function, drop_self=True)
    module_constants = {}
    for k, v in vars(inspect.getmodule(function) or cdp).items():
        if not k.startswith("_"):
            module_constants.setdefault(id(v), []).append(k)
    missing = []
    for n, kind, default, _ in runtime:
        if kind in ("*args", "**kwargs") or (default == NO_DEFAULT and kind != "keyword"):
            continue
        if not re.search(rf"\b{re.escape(n)}\b", body):
            missing.append(n)
        elif default not in (None, NO_DEFAULT) and not doc.startswith(short + "("):
            texts = {repr(default), str(default)}
            texts.update(module_constants.get(id(default), []))
            if not any(t in doc for t in texts):
                missing.append(f"{n}'s default {default!r}")
    if OPTION_METHODS.get(short, False) is not False and short in dir(_cdp):
        method = OPTION_METHODS[short]
        missing += [o["name"] for o in _cdp.polygonize_options()
                    if (method is None or method in o["methods"]) and not re.search(rf"\b{o['name']}\b", doc)]
    assert not missing, f"{name}: the docstring does not name {', '.join(missing)}"
