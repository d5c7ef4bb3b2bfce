"""FEBio's log tables (``<logfile>``'s node_data, element_data and rigid_body_data) as CSV
files of a run:
``Simulation.add_logfile`` asks for one, ``RunOutput`` writes it (``io/run_output.py``).

One table per request, in the long layout a pandas user reads with ``pd.read_csv``: the
column ``time``, then ``node`` (or ``element``: FEBio's 1-based id, or the request's own
``ids``), then one column per variable, one row per item and written frame (the run's
frames, the first at the start time included). FEBio's names:

- node_data: ``x, y, z`` (current position), ``ux, uy, uz`` (displacement), ``vx, vy, vz``
  (velocity), ``Rx, Ry, Rz`` (reaction force: the solve's gradient at the DOFs a support or
  prescribed motion holds, 0 elsewhere);
- element_data: ``sx, sy, sz, sxy, syz, sxz`` (Cauchy stress), ``s1, s2, s3`` (its principal
  values, s1 >= s2 >= s3), ``Ex, Ey, Ez, Exy, Eyz, Exz`` (Green-Lagrange strain), ``E1, E2,
  E3`` (its principal values), ``J`` (volume ratio); each the mean over the element's
  integration points, as FEBio's log takes it (principal values per point, then their mean;
  the VTU series' cell data weights the points by their volume: the same on an undistorted
  element);
- rigid_body_data (one row per rigid body, ``body`` its id): ``x, y, z`` (the centre),
  ``vx, vy, vz``, ``thx, thy, thz`` (the rotation vector), ``omx, omy, omz`` (the angular
  velocity), ``qx, qy, qz, qw`` (the quaternion), ``R11`` .. ``R33``, ``Fx, Fy, Fz`` and
  ``Mx, My, Mz`` (the force and moment its held DOFs' supports apply, as in forces.csv).

The table is appended frame by frame, each frame's rows in one write, flushed and fsynced;
the checkpoint counts its lines, so a resumed run first cuts it back to the frames the
checkpoint has (a frame written after it, or half written when the run was killed) and then
goes on appending (``checkpoint_history.jsonl`` is kept the same way).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tissuesim.errors import InputError
from tissuesim.io.atomic import write_text_atomic
from tissuesim.validate import short

__all__ = [
    "LogRequest", "LogTable", "make_request", "NODE_DATA", "ELEMENT_DATA", "RIGID_BODY_DATA",
    "KINDS",
]  # fmt: skip

#: FEBio's node_data variables tissuesim writes -> what they are
NODE_DATA = {
    **{c: f"{c} coordinate of the current position" for c in "xyz"},
    **{f"u{c}": f"{c} displacement" for c in "xyz"},
    **{f"v{c}": f"{c} velocity" for c in "xyz"},
    **{f"R{c}": f"{c} reaction force" for c in "xyz"},
}
_PAIRS = {"x": (0, 0), "y": (1, 1), "z": (2, 2), "xy": (0, 1), "yz": (1, 2), "xz": (0, 2)}
#: FEBio's element_data variables tissuesim writes -> what they are
ELEMENT_DATA = {
    **{f"s{k}": f"Cauchy stress {k}" for k in _PAIRS},
    **{f"s{k}": f"principal Cauchy stress {k}" for k in "123"},
    **{f"E{k}": f"Green-Lagrange strain {k}" for k in _PAIRS},
    **{f"E{k}": f"principal Green-Lagrange strain {k}" for k in "123"},
    "J": "volume ratio",
}
#: FEBio's rigid_body_data variables tissuesim writes -> what they are
RIGID_BODY_DATA = {
    **{c: f"{c} coordinate of the centre" for c in "xyz"},
    **{f"v{c}": f"{c} velocity of the centre" for c in "xyz"},
    **{f"th{c}": f"{c} component of the rotation vector (rad)" for c in "xyz"},
    **{f"om{c}": f"{c} angular velocity (rad/s)" for c in "xyz"},
    **{f"q{c}": f"{c} component of the rotation quaternion" for c in "xyzw"},
    **{f"R{i}{k}": f"rotation matrix entry {i}{k}" for i in "123" for k in "123"},
    **{f"F{c}": f"{c} force its held DOFs' supports apply (N)" for c in "xyz"},
    **{f"M{c}": f"{c} moment about the centre its held DOFs' supports apply (N m)" for c in "xyz"},
}
KINDS = {"node_data": NODE_DATA, "element_data": ELEMENT_DATA, "rigid_body_data": RIGID_BODY_DATA}
#: the id column of each kind
ID_COLUMN = {"node_data": "node", "element_data": "element", "rigid_body_data": "body"}
_FILE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


@dataclass(frozen=True)
class LogRequest:
    """One table: ``kind`` ("node_data" / "element_data"), its variables ``data``, the FEM
    body, the rows of its mesh (vertices or cells; None: all), the ids written for them and
    the file name in the output directory."""

    kind: str
    data: tuple[str, ...]
    body: str
    items: np.ndarray | None
    ids: np.ndarray | None
    file: str

    def header(self) -> str:
        return ",".join(["time", ID_COLUMN[self.kind], *self.data]) + "\n"


def make_request(
    kind: Any, data: Any, body: str, n_items: int, items: Any, ids: Any, file: Any, taken: set
) -> LogRequest:
    """A LogRequest checked (InputError in one line): known kind and variables, items in
    range, as many ids as items, a plain file name no other request or output file has."""
    from tissuesim.io.manifest import OUTPUT_FILES
    from tissuesim.validate import choice, indices

    kind = choice(kind, "kind", list(KINDS))
    names = [data] if isinstance(data, str) else data
    if not isinstance(names, (list, tuple)) or not names:
        raise InputError(f"data must be a list of {kind} variable names, not {short(data)}")
    for name in names:
        if name not in KINDS[kind]:
            raise InputError(
                f"data: {short(name)} is not a {kind} variable tissuesim writes; it writes "
                f"{', '.join(KINDS[kind])}"
            )
    if len(set(names)) < len(names):
        raise InputError(f"data names a variable twice: {short(names)}")
    what = {"node_data": "vertex", "element_data": "cell"}.get(kind, "rigid body")
    rows = None if items is None else indices(items, "items", n_items, what=what)
    if rows is not None and not rows.size:
        raise InputError("items is empty: give the rows to log, or none for all of them")
    count = n_items if rows is None else rows.size
    labels = None
    if ids is not None:
        labels = indices(ids, "ids", np.iinfo(np.int64).max, what="id")
        if labels.size != count:
            raise InputError(f"ids: {labels.size} ids for {count} items; give one per item")
    if file is None:
        file = f"{kind}_{len(taken) + 1}.csv"
    if not isinstance(file, str) or not _FILE.fullmatch(file):
        raise InputError(
            f"file must be a plain file name in the output directory (letters, digits, _ . -), "
            f"not {short(file)}"
        )
    if file in taken or file in OUTPUT_FILES:
        raise InputError(f"file {file!r} is written by another table or by the run itself")
    return LogRequest(kind, tuple(names), body, rows, labels, file)


def _principal(T: np.ndarray) -> np.ndarray:
    return np.linalg.eigvalsh(T)[:, ::-1]  # s1 >= s2 >= s3


def _padded(T: np.ndarray) -> np.ndarray:
    """(k, 3, 3) from a 2D body's (k, 2, 2) tensors (zeros out of the plane)."""
    if T.shape[-1] == 3:
        return T
    out = np.zeros((len(T), 3, 3))
    out[:, :2, :2] = T
    return out


def _columns3(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    if a.shape[1] == 3:
        return a
    return np.hstack([a, np.zeros((len(a), 3 - a.shape[1]))])


def node_values(sim: Any, request: LogRequest) -> dict[str, np.ndarray]:
    """The node_data variables of ``request`` now, one value per item."""
    b, c, v = sim.body_state(request.body)
    rest = b.mesh.points
    d = rest.shape[1]
    x = _columns3(c.reshape(-1, d))
    u = x - _columns3(rest)
    vel = _columns3(v.reshape(-1, d))
    out: dict[str, np.ndarray] = {}
    react = None
    if any(n.startswith("R") for n in request.data):
        react = _columns3(reactions(sim, request.body))
    for name in request.data:
        k = "xyz".index(name[-1])
        source = {"u": u, "v": vel, "R": react}.get(name[0], x) if len(name) == 2 else x
        out[name] = source[:, k]
    if request.items is not None:
        out = {k: a[request.items] for k, a in out.items()}
    return out


def reactions(sim: Any, body: str) -> np.ndarray:
    """(n, d) reaction force per vertex of FEM body ``body``: the last solve's gradient at the
    DOFs an active support or prescribed motion holds, 0 elsewhere (their sums are the
    forces in forces.csv)."""
    b, c, _ = sim.body_state(body)
    s, g = sim.system, sim._last_gradient
    d = b.dim
    out = np.zeros((b.mesh.n_points, d))
    j = s.index(b.name)
    if g is None or g.size != s.n_dofs:
        return out
    gj = g[s.tangent_slices[j]].reshape(-1, d)
    held = np.zeros((b.mesh.n_points, d), dtype=bool)
    active = {n for n, _ in b.active_conditions()}
    for name, cond in b.conditions:
        if name in active:
            comps = range(d) if cond.components is None else list(cond.components)
            held[np.ix_(np.asarray(cond.vertices), comps)] = True
    out[held] = gj[held]
    return out


def element_values(sim: Any, request: LogRequest) -> dict[str, np.ndarray]:
    """The element_data variables of ``request`` now, one value per item: each the mean over
    the element's integration points, as FEBio's log takes it (principal values per point,
    then their mean)."""
    b, c, _ = sim.body_state(request.body)
    fields = b.quadrature_fields(c)  # a body of regions: region by region (cell_means)
    tensors = {
        "s": _padded(np.asarray(fields["cauchy_stress"])),
        "E": _padded(np.asarray(fields["green_strain"])),
    }

    def mean(values: np.ndarray) -> np.ndarray:
        values = b.cell_means(values)
        return values if request.items is None else values[request.items]

    out: dict[str, np.ndarray] = {}
    principal: dict[str, np.ndarray] = {}
    for name in request.data:
        if name == "J":
            out[name] = mean(np.asarray(fields["J"], dtype=float))
            continue
        T = tensors[name[0]]
        if name[1:] in _PAIRS:
            i, k = _PAIRS[name[1:]]
            out[name] = mean(T[:, i, k])
            continue
        if name[0] not in principal:
            principal[name[0]] = _principal(T)
        out[name] = mean(principal[name[0]][:, int(name[1]) - 1])
    return out


def rigid_values(sim: Any, request: LogRequest) -> dict[str, np.ndarray]:
    """The rigid_body_data variables of ``request`` now, one value per rigid body (in the
    order they were added; ``items`` picks some)."""
    from scipy.spatial.transform import Rotation

    s, state = sim.system, sim.state
    forces = sim._rigid_forces(sim._last_gradient)
    rows = []
    for r, sc, st in zip(s.rigid, s.rigid_config_slices, s.rigid_tangent_slices, strict=True):
        z, v = state.x[sc], state.v[st]
        R = z[3:12].reshape(3, 3)
        turn = Rotation.from_matrix(R)
        row = dict(zip("xyz", z[:3], strict=True))
        row.update({f"v{c}": v[k] for k, c in enumerate("xyz")})
        row.update({f"th{c}": a for c, a in zip("xyz", turn.as_rotvec(), strict=True)})
        row.update({f"om{c}": v[3 + k] for k, c in enumerate("xyz")})
        row.update({f"q{c}": a for c, a in zip("xyzw", turn.as_quat(), strict=True)})
        row.update({f"R{i + 1}{k + 1}": R[i, k] for i in range(3) for k in range(3)})
        row.update({f"F{c}": a for c, a in zip("xyz", forces[r.name], strict=True)})
        row.update({f"M{c}": a for c, a in zip("xyz", forces[f"{r.name}.moment"], strict=True)})
        rows.append(row)
    picked = rows if request.items is None else [rows[i] for i in request.items]
    return {name: np.array([row[name] for row in picked]) for name in request.data}


def check_uncut(sim: Any, request: LogRequest) -> None:
    """A logged body is never cut nor torn (its vertices and elements would be others than
    the rows asked for): InputError in one line when the run starts."""
    if request.kind == "rigid_body_data":
        return
    body = request.body
    cutters = [c.name for c in sim.organ_cuts if c.body == body]
    cutters += [f"{body}.tear" for t in sim.organ_tears if t.body == body]
    if sim.bodies[body].cut_state is not None:
        cutters.append("cut_body")
    if cutters:
        raise InputError(
            f"the log table {request.file!r} is of body {body!r}, which is cut ({cutters[0]}): "
            "a cut changes its nodes and elements; log another body, or leave the cut out"
        )


class LogTable:
    """The CSV file of one request in a run's directory: ``open`` (afresh, or cut back to
    ``keep`` lines when a run resumes), then ``write(sim, t)`` once per frame."""

    def __init__(self, request: LogRequest) -> None:
        self.request = request
        self.path: Path | None = None
        self.lines = 0  # lines in the file (the header included)

    def open(self, directory: Path, keep: int | None = None) -> None:
        self.path = directory / self.request.file
        if keep is None:
            write_text_atomic(self.path, self.request.header())
            self.lines = 1
            return
        try:
            with open(self.path, encoding="utf-8") as f:
                lines = [f.readline() for _ in range(keep)]
        except OSError:
            lines = []
        if len(lines) < 1 or lines[0] != self.request.header() or not lines[-1].endswith("\n"):
            raise InputError(
                f"{self.path} does not hold the {keep} lines the checkpoint counts; it may be "
                "damaged: run without --resume to start afresh"
            )
        write_text_atomic(self.path, "".join(lines))
        self.lines = keep

    def write(self, sim: Any, t: float) -> None:
        r = self.request
        read = {"node_data": node_values, "element_data": element_values}
        values = read.get(r.kind, rigid_values)(sim, r)
        n = len(next(iter(values.values())))
        if r.ids is not None:
            ids = r.ids
        elif r.items is not None:
            ids = r.items + 1
        else:
            ids = np.arange(1, n + 1)
        time = repr(float(t))
        table = np.column_stack([values[k] for k in r.data])
        rows = [
            ",".join([time, str(int(i)), *map(repr, map(float, row))])
            for i, row in zip(ids, table, strict=True)
        ]
        with open(self.path, "a", encoding="utf-8", newline="") as f:
            f.write("\n".join(rows) + "\n")
            f.flush()
            os.fsync(f.fileno())
        self.lines += len(rows)
