"""Argument errors that name the culprit.

pybind11 answers a call whose arguments do not convert with "incompatible function arguments" and the whole
signature. Every function and method of the compiled module is wrapped here so that such a call raises the same
error class naming the argument as the user wrote it: `replicate(): world_count=2147483648 is out of the range of
a 32-bit int`, `from_mujoco(): precision=1 must be a Precision (Precision.Float64, Precision.Float32), got int`.
A call that converts pays one Python frame.
"""

import functools
import numbers
import re

import numpy as np

INT32 = (-(2**31), 2**31 - 1)


def split_top_level(text):
    """Splits an argument list at the commas outside brackets (tools/make_stub.py reads signatures with it too)."""
    parts, depth, current = [], 0, ""
    for ch in text:
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == "," and depth == 0:
            parts.append(current.strip())
            current = ""
        else:
            current += ch
    return parts + [current.strip()] if current.strip() else parts


def _parameters(message):
    """(name, type) of each parameter of the one overload the message lists; None where it lists several."""
    overloads = re.findall(r"^\s*\d+\. [\w.]*\((.*)\)(?: -> .*)?$", message, re.MULTILINE)
    if len(overloads) != 1:
        return None
    parameters = []
    for part in split_top_level(overloads[0]):
        if part == "*":
            continue
        head = part.split("=", 1)[0] if "=" in part.split(":", 1)[-1] else part
        name, _, kind = head.partition(":")
        parameters.append((name.strip(), kind.strip()))
    return parameters


def _shown(value):
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _problem(kind, value, module):
    """Why `value` is no `kind` (pybind11's name of a parameter type), or None where it is one."""
    optional = re.fullmatch(r"Optional\[(.*)\]", kind)
    if optional:
        return None if value is None else _problem(optional.group(1), value, module)
    if value is None:
        return f"must be {_described(kind)}, got None"
    if kind == "int":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            return f"must be an int, got {type(value).__name__}"
        if not INT32[0] <= int(value) <= INT32[1]:
            return f"is out of the range of a 32-bit int [{INT32[0]}, {INT32[1]}]"
        return None
    if kind == "float":
        return None if isinstance(value, numbers.Real) else f"must be a number, got {type(value).__name__}"
    if kind == "bool":
        return None if isinstance(value, (bool, np.bool_)) else f"must be True or False, got {type(value).__name__}"
    if kind == "str":
        return None if isinstance(value, str) else f"must be a str, got {type(value).__name__}"
    if kind.startswith("numpy.ndarray") or kind.startswith("List[float"):
        return _array_problem(kind, value)
    if kind.startswith("Callable"):
        return None if callable(value) else f"must be callable, got {type(value).__name__}"
    if kind.startswith("novaphy._novaphy."):
        cls = getattr(module, kind.rsplit(".", 1)[1], None)
        if isinstance(cls, type) and not isinstance(value, cls):
            return f"must be {_described(kind, module)}, got {type(value).__name__}"
    return None


def _described(kind, module=None):
    size = re.search(r"\[(\d+)(?:, 1)?\]\]?$", kind)
    if kind.startswith("numpy.ndarray") or kind.startswith("List[float"):
        return f"an array of {size.group(1)} numbers" if size else "an array of numbers"
    name = kind.rsplit(".", 1)[-1]
    cls = getattr(module, name, None) if module else None
    members = getattr(cls, "__members__", None)
    if members:
        return f"a {name} ({', '.join(f'{name}.{m}' for m in members)})"
    return {"int": "an int", "float": "a number", "bool": "True or False", "str": "a str"}.get(name, f"a {name}")


def _array_problem(kind, value):
    try:
        array = np.asarray(value)
    except Exception:
        return f"must be an array of numbers, got {type(value).__name__}"
    if array.dtype.kind not in "biuf":
        element = {"U": "str", "S": "bytes", "O": "objects"}.get(array.dtype.kind, str(array.dtype))
        return f"must be an array of numbers, got an array of {element}"
    size = re.search(r"\[(\d+)(?:, 1)?\]\]?$", kind)
    if size and array.size != int(size.group(1)):
        return f"must hold {size.group(1)} numbers, got shape {array.shape}"
    return None


def _explained(name, error, args, kwargs, module, setter):
    """The error naming the first argument that does not convert, or None where none is found."""
    message = str(error)
    constructor = "incompatible constructor arguments" in message
    if "incompatible function arguments" not in message and not constructor:
        return None
    parameters = _parameters(message)
    if parameters is None:
        return None
    if constructor:
        args = args[1:]  # the constructor's signature leaves self out
    given = list(zip(parameters, args)) + [(p, kwargs[p[0]]) for p in parameters if p[0] in kwargs]
    for (parameter, kind), value in given:
        if parameter in ("self", "arg0") and not constructor and value is args[0]:
            continue
        problem = _problem(kind, value, module)
        if problem:
            error_class = ValueError if "out of the range" in problem else TypeError
            if setter:
                return error_class(f"{name} = {_shown(value)}: {problem}")
            shown = parameter if parameter.startswith("arg") else f"{parameter}={_shown(value)}"
            return error_class(f"{name}(): {shown} {problem}")
    return None


def _wrapped(name, function, module, setter=False):
    @functools.wraps(function)
    def call(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except TypeError as error:
            explained = _explained(name, error, args, kwargs, module, setter)
            if explained is None:
                raise
            raise explained from None

    return call


def name_the_culprits(module):
    """Wraps the module's functions and its classes' methods and property setters (in place)."""
    for name, value in list(vars(module).items()):
        if name.startswith("_"):
            continue
        if isinstance(value, type) and not issubclass(value, BaseException) and not hasattr(value, "__members__"):
            for attr, member in list(vars(value).items()):
                if attr.startswith("__") and attr != "__init__":
                    continue
                label = name if attr == "__init__" else f"{name}.{attr}"
                if isinstance(member, property) and member.fset is not None:
                    setattr(value, attr, property(member.fget, _wrapped(label, member.fset, module, True), member.fdel,
                                                  member.__doc__))
                elif isinstance(member, staticmethod):
                    setattr(value, attr, staticmethod(_wrapped(label, member.__func__, module)))
                elif callable(member) and not isinstance(member, type):
                    setattr(value, attr, _wrapped(label, member, module))
        elif callable(value) and not isinstance(value, type):
            setattr(module, name, _wrapped(name, value, module))
