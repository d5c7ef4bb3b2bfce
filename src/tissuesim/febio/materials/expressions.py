"""FEBio's ``hyperelastic`` and ``uncoupled hyperelastic`` (``FEGenericHyperelastic``,
``FEGenericHyperelasticUC``): a strain-energy density ``<W>`` written in FEBio's math syntax,
read as tissuesim's ``energy`` law (``materials/energy_law``).

``<W>`` is ``name = number; ...; expression``: the assignments are the law's parameters, the
expression W in FEBio's variables I1, I2 and J (the positions X, Y, Z are refused). FEBio's
``ln`` is the natural logarithm and its ``log`` the decimal one (written ln(x)/ln(10) here).
The uncoupled law's W is in the deviatoric invariants, I1b and I2b here, plus FEBio's bulk term
of ``k`` and ``pressure_model`` (k/2 (ln J)^2, k/4 (J^2 - 1 - 2 ln J), k/2 (J - 1)^2); tissuesim
runs it with the displacement formulation (FEBio its three-field element: a note says so).
"""

from __future__ import annotations

import re

from tissuesim.febio.model import FebModel, _floats, _once, _unsupported
from tissuesim.febio.xml import Node

__all__ = ["GENERIC", "generic_hyperelastic"]

#: FEBio's generic laws -> whether uncoupled
GENERIC = {"hyperelastic": False, "uncoupled hyperelastic": True}
#: FEBio's math functions tissuesim's energy law takes (``log`` is FEBio's log10)
_FUNCTIONS = {"ln", "exp", "sqrt", "sin", "cos", "tan", "sinh", "cosh", "tanh", "atan", "log"}
#: the bulk term of each pressure_model, as an energy in J and k
_BULK = {
    "default": "k/2*ln(J)**2", "0": "k/2*ln(J)**2",
    "NIKE3D": "k/4*(J**2 - 1 - 2*ln(J))", "1": "k/4*(J**2 - 1 - 2*ln(J))",
    "Abaqus": "k/2*(J - 1)**2", "2": "k/2*(J - 1)**2",
    "Abaqus (GOH)": "k/4*(J**2 - 1 - 2*ln(J))", "3": "k/4*(J**2 - 1 - 2*ln(J))",
}  # fmt: skip
_RESERVED = {"I1", "I2", "I3", "J", "I1b", "I2b", "pi", "e", "psi", "model", "k"}


def generic_hyperelastic(model: FebModel, mat: Node, kind: str) -> tuple[dict, float]:
    """(the energy law's parameters, the density) of a ``hyperelastic`` material."""
    uncoupled = GENERIC[kind]
    parts = _once(mat)
    density, k, pressure = 1.0, None, "default"
    for p in mat.children:
        if p.tag == "W":
            continue
        if p.children or "lc" in p.attrib or p.attrib.get("type") not in (None, "const"):
            raise _unsupported(p, "a material parameter that is a field, a curve or a table")
        if p.tag == "density":
            density = float(_floats(p, 1)[0])
        elif p.tag == "print_derivs":
            model.note(p, "FEBio prints the derivatives of W to its log; tissuesim does not")
        elif uncoupled and p.tag == "k":
            k = float(_floats(p, 1)[0])
        elif uncoupled and p.tag == "pressure_model":
            pressure = p.text.strip()
            if pressure not in _BULK:
                raise p.error(f"pressure_model {pressure!r}: FEBio's are {sorted(_BULK)[4:]}")
        else:
            takes = "W, density" + (", k, pressure_model" if uncoupled else "")
            raise p.error(f"parameter {p.tag!r} of {kind!r}: it takes {takes}")
    if "W" not in parts:
        raise mat.error(f"a {kind!r} material needs its strain-energy density <W>")
    node = parts["W"]
    statements = [s.strip() for s in node.text.split(";") if s.strip()]
    if not statements:
        raise node.error("<W> is empty")
    params: dict = {}
    for statement in statements[:-1]:
        name, _, value = statement.partition("=")
        name = name.strip()
        if not re.fullmatch(r"[A-Za-z_]\w*", name) or not value.strip():
            raise node.error(f"<W>: {statement!r} is not 'name = number'")
        try:
            params[name] = float(value)
        except ValueError:
            raise node.error(f"<W>: {name} = {value.strip()!r}: a parameter is a number") from None
    renamed = {n: (f"p_{n}" if n in _RESERVED else n) for n in params}
    variables = {"I1": "I1b", "I2": "I2b"} if uncoupled else {"I1": "I1", "I2": "I2", "J": "J"}

    def word(match: re.Match) -> str:
        name = match.group(0)
        if name in variables:
            return variables[name]
        if name in renamed:
            return renamed[name]
        if name == "log":
            return "0.4342944819032518*ln"
        if name in _FUNCTIONS:
            return name
        if name in ("X", "Y", "Z"):
            raise node.error(f"<W>: the position {name} is not supported by tissuesim")
        what = "J (the uncoupled W is in I1 and I2)" if name == "J" else repr(name)
        raise node.error(f"<W>: unknown name {what}; W takes I1, I2"
                         + ("" if uncoupled else ", J") + " and its parameters")  # fmt: skip

    psi = re.sub(r"(?<![\w.])[A-Za-z_]\w*", word, statements[-1])
    params = {renamed[n]: v for n, v in params.items()}
    if uncoupled:
        if k is None:
            raise mat.error(f"a {kind!r} material needs its bulk modulus <k>")
        psi = f"{psi} + {_BULK[pressure]}"
        params["k"] = k
        model.note(mat, "FEBio runs an uncoupled hyperelastic law with its three-field element; "
                   "tissuesim with the displacement formulation")  # fmt: skip
    return {"psi": psi, **params}, density
