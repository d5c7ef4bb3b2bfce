"""Property-based fuzzing (Hypothesis) of what users hand tissuesim: scene files, expressions,
meshes, API arguments and output directories. Every case must end cleanly or with one clear
error line (see ``harness.py`` for the full list of checks).

Default (CI): a few dozen cases per kind, derandomised so CI is stable. Long mode for
releases: ``TISSUESIM_FUZZ=long TISSUESIM_FUZZ_REPORT=fuzz.json python -m pytest tests/fuzz``
(random seeds, 1,500 cases per test or ``TISSUESIM_FUZZ_EXAMPLES``; the report counts them
per kind).
"""

from __future__ import annotations

import copy
import os
import shutil
import tempfile
import tomllib
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tissuesim as ts
from tissuesim.errors import InputError
from tissuesim.scene.expressions import compile_vector

from .harness import LONG, run_case, to_toml, write_report

SHORT_EXAMPLES = 40
LONG_EXAMPLES = int(os.environ.get("TISSUESIM_FUZZ_EXAMPLES", "1500"))

FUZZ = settings(
    max_examples=LONG_EXAMPLES if LONG else SHORT_EXAMPLES,
    deadline=None,
    derandomize=not LONG,
    suppress_health_check=list(HealthCheck),
    database=None,
)


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    write_report()
    _sandbox()
    shutil.rmtree(_SANDBOXES.pop(), ignore_errors=True)


# -- base scenes: one of each kind, small enough to run a step in well under a second ----------
BASES = {
    "fem2d": """
[mesh]
generator = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 1.0]
divisions = [3, 3]
[material]
model = "neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[simulation]
density = 1.0
integrator = "backward_euler"
time_step = 0.01
[[dirichlet]]
vertices = { on_plane = { axis = 0, value = 0.0 } }
displacement = ["0.1 * t", "0"]
[[traction]]
facets = { on_plane = { axis = 0, value = 1.0 } }
traction = [1.0, "sin(t)"]
[gravity]
acceleration = [0.0, -9.81]
[run]
steps = 2
""",
    "fem3d": """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 0.2, 0.2]
divisions = [3, 1, 1]
[material]
model = "course_neo_hookean"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[simulation]
density = 1.0
integrator = "quasistatic"
time_step = 0.1
[[dirichlet]]
vertices = { tagged = "xmin" }
[[nodal_forces]]
vertices = { where = "x > 0.99" }
force = [0.0, 0.0, -0.01]
[run]
steps = 2
every = 1
""",
    "frames": """
[frames]
type = "rigid"
shape = "wendland"
grid = { lower = [0.1, 0.1, 0.0], upper = [0.1, 0.1, 0.6], counts = [1, 1, 3] }
[region]
box = { lower = [0.0, 0.0, 0.0], upper = [0.2, 0.2, 0.6] }
spacing = 0.1
[material]
model = "stvk"
youngs_modulus = 1e5
poisson_ratio = 0.3
[simulation]
density = 1000.0
integrator = "backward_euler"
time_step = 0.02
[gravity]
acceleration = [0.0, -9.81, 0.0]
[[fixed_frames]]
frames = { on_plane = { axis = 2, value = 0.0 } }
[run]
steps = 2
""",
    "bodies": """
[simulation]
integrator = "quasistatic"
time_step = 0.1
[[bodies]]
name = "muscle"
material = { model = "neo_hookean", youngs_modulus = 50000.0, poisson_ratio = 0.45 }
density = 1060.0
fix = { where = "z < 1e-9" }
[bodies.mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.06, 0.04, 0.03]
divisions = [2, 2, 1]
[[bodies]]
name = "fat"
material = { model = "neo_hookean", youngs_modulus = 5000.0, poisson_ratio = 0.45 }
density = 950.0
[bodies.mesh]
generator = "box"
lower = [0.0, 0.0, 0.03]
upper = [0.06, 0.04, 0.05]
divisions = [2, 2, 1]
[[attachments]]
body = "fat"
to = "muscle"
name = "glue"
[[graspers]]
body = "fat"
name = "grasper"
vertices = { tagged = "zmax" }
displacement = ["0.004 * min(t, 1)", "0", "0.003 * min(t, 1)"]
[run]
steps = 2
""",
}
BASES["contact"] = """
[mesh]
generator = "box"
lower = [0.0, 0.0, 0.0]
upper = [1.0, 1.0, 0.5]
divisions = [2, 2, 1]
[material]
model = "neo_hookean"
youngs_modulus = 1e4
poisson_ratio = 0.3
[simulation]
integrator = "quasistatic"
time_step = 0.1
[[dirichlet]]
vertices = { tagged = "zmin" }
[contact]
dhat = 0.01
friction = 0.3
[[obstacles]]
name = "probe"
sphere = { center = [0.5, 0.5, 0.71], radius = 0.2, refinement = 1 }
translation = ["0", "0", "-0.02 * t"]
[[obstacles]]
name = "wall"
plane = { point = [1.05, 0.5, 0.25], normal = [-1, 0, 0], size = 2.0 }
[run]
steps = 2
"""
PARSED = {k: tomllib.loads(v) for k, v in BASES.items()}

NASTY_NUMBERS = [
    0,
    -1,
    1,
    2,
    3,
    2.5,
    -0.0,
    1e-300,
    1e300,
    10**400,
    2**63,
    float("inf"),
    float("-inf"),
    float("nan"),
    0.5,
    1e-12,
]
NASTY_STRINGS = [
    "",
    "x",
    "x / 0",
    "nan",
    "rectangle",
    "box",
    "neo_hookean",
    "quasistatic",
    "explicit",
    "9**9**9",
    "__import__('os')",
    "().__class__",
    "../../etc/passwd",
    "/dev/zero",
    "a" * 5000,
    "sin(",
    "t * 1e308",
    "log(x - 1)",
    "J",
    "zmax",
]
# text without lone surrogates (TOML cannot hold them: every such case would stop at parsing)
text = st.text(alphabet=st.characters(exclude_categories=("Cs",)), max_size=20)
leaf = st.one_of(
    st.sampled_from(NASTY_NUMBERS),
    st.sampled_from(NASTY_STRINGS),
    st.booleans(),
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.integers(min_value=-(10**20), max_value=10**20),
    text,
)
value = st.recursive(
    leaf,
    lambda inner: st.one_of(st.lists(inner, max_size=5), st.dictionaries(text, inner, max_size=3)),
    max_leaves=8,
)


def _paths(data, prefix=()):
    """Every (path, value) in a parsed scene: keys of tables, indices of arrays."""
    if isinstance(data, dict):
        for k, v in data.items():
            yield (*prefix, k), v
            yield from _paths(v, (*prefix, k))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            yield (*prefix, i), v
            yield from _paths(v, (*prefix, i))


@st.composite
def mutated_scene(draw):
    base = draw(st.sampled_from(sorted(PARSED)))
    data = copy.deepcopy(PARSED[base])
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p, _ in _paths(data)]
        path = draw(st.sampled_from(paths))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "delete", "rename", "add"]))
        if action == "replace":
            parent[path[-1]] = draw(value)
        elif action == "delete":
            del parent[path[-1]]
        elif action == "rename" and isinstance(parent, dict):
            parent[draw(text.filter(bool))] = parent.pop(path[-1])
        elif isinstance(parent, dict):
            parent[draw(text.filter(bool))] = draw(value)
    return base, data


_SANDBOXES: list[Path] = []


def _sandbox() -> Path:
    """A fresh directory for one case (the previous case's is removed first)."""
    while _SANDBOXES:
        shutil.rmtree(_SANDBOXES.pop(), ignore_errors=True)
    path = Path(tempfile.mkdtemp(prefix="tissuesim-fuzz-"))
    _SANDBOXES.append(path)
    return path


@FUZZ
@given(case=mutated_scene())
def test_mutated_scene_files(case):
    base, data = case
    sandbox = _sandbox()
    try:
        text = to_toml(data)
    except TypeError:
        return  # a value TOML cannot hold
    (sandbox / "scene.toml").write_text(text)
    run_case(
        f"scene {base}",
        sandbox,
        ["run", "scene.toml", "--out", "out", "--quiet", "--steps", "2", "--no-render"],
        {"scene.toml"},
    )


@FUZZ
@given(text=st.binary(max_size=300))
def test_garbage_scene_files(text):
    sandbox = _sandbox()
    (sandbox / "scene.toml").write_bytes(text)
    code, _ = run_case(
        "scene bytes", sandbox, ["run", "scene.toml", "--out", "out", "--quiet"], {"scene.toml"}
    )
    assert code == 2


expression = st.recursive(
    st.one_of(
        st.sampled_from(
            [
                "x",
                "y",
                "z",
                "t",
                "pi",
                "e",
                "0",
                "1",
                "1e308",
                "-1",
                "0.5",
                "q",
                "__class__",
                "inf",
                "nan",
            ]
        ),
        st.floats(allow_nan=False, width=32).map(repr),
    ),
    lambda inner: st.one_of(
        st.tuples(
            inner, st.sampled_from(["+", "-", "*", "/", "**", "%", "//", "<", "==", " "]), inner
        ).map(lambda p: f"({p[0]} {p[1]} {p[2]})"),
        st.tuples(
            st.sampled_from(
                ["sin", "exp", "log", "sqrt", "abs", "max", "where", "open", "eval", "lambda x:"]
            ),
            inner,
        ).map(lambda p: f"{p[0]}({p[1]})"),
        inner.map(lambda s: f"-{s}"),
        inner.map(lambda s: f"{s}.real"),
        inner.map(lambda s: f"[{s}]"),
    ),
    max_leaves=12,
)


@FUZZ
@given(parts=st.lists(expression, min_size=1, max_size=4))
def test_expressions(parts):
    """As the API compiles them, and in a scene's prescribed displacement."""
    from .harness import COUNTS, time_limit

    COUNTS["expression"] += 1
    X = np.random.default_rng(0).uniform(-1, 1, (5, 3))
    with time_limit(10):
        try:
            f = compile_vector(parts, len(parts), "displacement")
            values = f(X, 0.5)
            assert values.shape == (5, len(parts))
        except InputError:
            pass
    sandbox = _sandbox()
    data = copy.deepcopy(PARSED["fem2d"])
    data["dirichlet"][0]["displacement"] = (parts + ["0", "0"])[:2]
    (sandbox / "scene.toml").write_text(to_toml(data))
    run_case(
        "scene expression",
        sandbox,
        ["run", "scene.toml", "--out", "out", "--quiet", "--no-render"],
        {"scene.toml"},
    )


@st.composite
def raw_mesh(draw):
    d = draw(st.sampled_from([2, 3]))
    n = draw(st.integers(1, 12))
    coords = st.one_of(
        st.floats(-2, 2, width=32), st.sampled_from([0.0, 1.0, float("nan"), float("inf"), 1e-13])
    )
    points = draw(st.lists(st.lists(coords, min_size=d, max_size=d), min_size=n, max_size=n))
    k = draw(st.sampled_from([d + 1, d + 1, d + 1, d, d + 2]))
    m = draw(st.integers(0, 8))
    cells = draw(
        st.lists(st.lists(st.integers(-1, n), min_size=k, max_size=k), min_size=m, max_size=m)
    )
    duplicate = draw(st.booleans())
    if duplicate and points:
        points = points + [list(points[0])]
    return np.array(points, dtype=float), np.array(cells, dtype=np.int64).reshape(m, k)


@st.composite
def perturbed_mesh(draw):
    """A valid generated mesh with a few of the defects real files have: a duplicated
    (unwelded) vertex, a stray vertex, a flipped or collapsed element, a moved vertex."""
    d = draw(st.sampled_from([2, 3]))
    mesh = ts.rectangle((0, 0), (1, 1), (2, 2)) if d == 2 else ts.box(divisions=(2, 1, 1))
    points, cells = mesh.points.copy(), mesh.cells.copy()
    for _ in range(draw(st.integers(0, 3))):
        defect = draw(st.sampled_from(["seam", "stray", "flip", "collapse", "move", "nan"]))
        e = draw(st.integers(0, len(cells) - 1))
        if defect == "seam":  # element e gets its own copy of its first vertex
            points = np.vstack([points, points[cells[e, 0]]])
            cells[e, 0] = len(points) - 1
        elif defect == "stray":
            points = np.vstack([points, draw(st.sampled_from([[5.0] * d, points[0].tolist()]))])
        elif defect == "flip":
            cells[e, [0, 1]] = cells[e, [1, 0]]
        elif defect == "collapse":
            cells[e, 1] = cells[e, 0]
        elif defect == "move":
            points[cells[e, 0]] += draw(st.sampled_from([1e-12, 0.3, -2.0, 1e6]))
        else:
            points[cells[e, 0], 0] = float("nan")
    return points, cells


@FUZZ
@given(mesh=st.one_of(raw_mesh(), perturbed_mesh()), fmt=st.sampled_from([".vtu", ".msh", ".mesh"]))
def test_mesh_files(mesh, fmt):
    """Random (often broken) meshes written to files: ``info`` and a scene that uses them."""
    points, cells = mesh
    sandbox = _sandbox()
    d = points.shape[1]
    kind = {3: "triangle", 4: "tetra", 2: "line", 5: "pyramid"}.get(cells.shape[1], "triangle")
    try:
        block = (
            [(kind, cells)] if len(cells) and cells.min() >= 0 and cells.max() < len(points) else []
        )
        meshio.write(
            sandbox / f"m{fmt}",
            meshio.Mesh(
                points if d == 3 else np.column_stack([points, np.zeros(len(points))]), block
            ),
        )
    except Exception:
        return  # meshio cannot write this one: nothing to read
    inputs = {f"m{fmt}"}
    run_case("mesh info", sandbox, ["info", f"m{fmt}"], inputs)
    scene = copy.deepcopy(PARSED["fem3d" if d == 3 else "fem2d"])
    scene["mesh"] = {"file": f"m{fmt}", "merge_coincident": True}
    scene["dirichlet"] = [{"vertices": {"boundary": True}}] if d == 3 else scene["dirichlet"]
    scene.pop("nodal_forces", None)
    scene.pop("traction", None)
    (sandbox / "scene.toml").write_text(to_toml(scene))
    run_case(
        "mesh scene",
        sandbox,
        ["run", "scene.toml", "--out", "out", "--quiet", "--no-render"],
        inputs | {"scene.toml"},
    )


API_VALUES = st.one_of(
    st.sampled_from(NASTY_NUMBERS),
    st.sampled_from(["auto", "x", ""]),
    st.none(),
    st.lists(st.sampled_from(NASTY_NUMBERS), max_size=4),
    st.just(np.array([True, False])),
    st.just(np.array([0.5, 1.0])),
)
API_KEYS = [
    "density",
    "integrator",
    "time_step",
    "max_step_halvings",
    "start_time",
    "backend",
    "gravity",
    "mass",
    "name",
]


NEWTON_KEYS = [
    "max_iterations",
    "armijo",
    "max_line_search",
    "gradient_tolerance",
    "hessian_projection",
    "linear_solver",
]
RUN_KEYS = ["steps", "every", "field", "render"]


@FUZZ
@given(
    kwargs=st.one_of(
        st.just({}), st.dictionaries(st.sampled_from(API_KEYS), API_VALUES, max_size=1)
    ),
    newton=st.one_of(
        st.just({}), st.dictionaries(st.sampled_from(NEWTON_KEYS), API_VALUES, max_size=1)
    ),
    vertices=st.one_of(st.just([0, 1, 2]), API_VALUES),
    run=st.one_of(st.just({}), st.dictionaries(st.sampled_from(RUN_KEYS), API_VALUES, max_size=1)),
)
def test_api_arguments(kwargs, newton, vertices, run):
    """The Python API, one bad argument at a time (the others valid, so each reaches the code
    that uses it): every bad argument is an InputError (a ValueError) naming it."""
    from .harness import COUNTS, OUTCOMES, time_limit

    COUNTS["api"] += 1
    sandbox = _sandbox()
    mesh = ts.rectangle((0, 0), (1, 1), (2, 2))
    material = ts.make_material("neo_hookean", youngs_modulus=1e3, poisson_ratio=0.3)
    run.setdefault("steps", 1)
    if isinstance(run["steps"], int) and not isinstance(run["steps"], bool):
        run["steps"] = min(run["steps"], 3)
    with time_limit(30):
        try:
            options = ts.NewtonOptions(**newton)
            sim = ts.Simulation(mesh, material, newton=options, **kwargs)
            sim.fix(sim.body().name, vertices)
            sim.add_gravity([0.0, -9.81])
            sim.run(output=sandbox / "out", progress=False, **{"render": False, **run})
            OUTCOMES["api: ran"] += 1
        except (InputError, ts.RunError) as exc:
            OUTCOMES[f"api: {type(exc).__name__}"] += 1
        except Exception as exc:  # noqa: BLE001 - any other exception is the failure we hunt
            raise AssertionError(f"{type(exc).__name__}: {exc}; {kwargs} {newton} {run}") from exc


@FUZZ
@given(
    kind=st.sampled_from(
        ["file", "under-file", "long-name", "summary-dir", "junk", "weird-chars", "dev-null"]
    )
)
def test_output_directories(kind):
    sandbox = _sandbox()
    (sandbox / "scene.toml").write_text(BASES["fem2d"])
    inputs = {"scene.toml"}
    out = "out"
    if kind == "file":
        (sandbox / "out").write_text("x")
        inputs.add("out")
    elif kind == "under-file":
        (sandbox / "out").write_text("x")
        inputs.add("out")
        out = "out/sub"
    elif kind == "long-name":
        out = "out/" + "d" * 300
    elif kind == "summary-dir":
        (sandbox / "out" / "summary.json").mkdir(parents=True)
    elif kind == "junk":
        (sandbox / "out").mkdir()
        (sandbox / "out" / "manifest.json").write_text('{"files": ["../scene.toml"], "series": 3}')
        inputs.add("out/manifest.json")
    elif kind == "weird-chars":
        out = "out/dir with spaces & ünïcode"
    elif kind == "dev-null":
        out = os.devnull
    code, text = run_case(
        f"output {kind}",
        sandbox,
        ["run", "scene.toml", "--out", out, "--quiet", "--no-render"],
        inputs,
    )
    assert (sandbox / "scene.toml").read_text() == BASES["fem2d"]
    if kind in ("file", "under-file", "long-name", "summary-dir", "dev-null"):
        assert code == 2, text
    else:
        assert code == 0, text
