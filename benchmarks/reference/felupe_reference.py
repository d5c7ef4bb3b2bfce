"""Independent reference values computed with FElupe (not with tissuesim).

What it computes (every number in ``benchmarks/results/felupe_reference.md``):

``cook``
    Cook's membrane, plane strain, dead shear traction on the right edge, tissuesim's
    ``neo_hookean`` energy ``psi = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2`` (F_33 = 1).
    Quantity: u_y at the top-right corner (48, 60).  Default load: mu = 80.194 MPa and a
    total vertical force of 100 N per mm thickness, i.e. t_y = 100/16 = 6.25 MPa per unit
    reference length (the load of de Souza Neto et al. 1996 / OpenGeoSys); nu = 0.3, 0.49,
    0.4999.  Formulations: mixed u-p-J (``NearlyIncompressible``: psi_hat(F) = mu/2 (I1 - 3)
    - mu ln J on the displacement, U(Jbar) = lam/2 (ln Jbar)^2 on the independent
    dilatation) on biquadratic quads (Q9, discontinuous bilinear p and J) and on quadratic
    triangles (P2, continuous linear p and J, Taylor-Hood); displacement-only P2 / Q9 as a
    cross-check for the compressible cases.
``cook-published``
    The same geometry with the parameters *and energies* of published results, to check the
    set-up against them and to quantify the effect of the energy:
    deal.II code gallery "Quasi-static finite-strain compressible elasticity" (mu = 0.4225
    MPa, nu = 0.3, total force 1 N, psi = mu/2 (Ibar1 - 3) + kappa/4 (J^2 - 1 - 2 ln J)) and
    OpenGeoSys LargeDeformation/CooksMembrane (E = 240.565 MPa, nu = 0.499, t = 6.25 MPa,
    psi = G/2 (Ibar1 - 3) + K/2 (J - 1)^2), each also with tissuesim's energy, plus the
    step-44-type energy at the default parameters.
``block``
    Bonded compression of the unit cube (mu = 1000 Pa, nu = 0.45, 0.49), bottom clamped, top
    clamped in x, y and moved by -0.2 in z.  Quantity: total vertical force on the top face
    (the force the top platen applies to the body, +z positive; it is negative).  One eighth
    of the cube is modelled (symmetry planes x = 0.5, y = 0.5 and z = 0.5, u_z = -0.1 on the
    mid-plane), quadratic mixed elements (Hex27 with discontinuous trilinear p and J;
    Tet10 Taylor-Hood as a cross-check); ``--block-model quarter`` models the full height.
``cantilever``
    Linear elastic (small strain) cantilever [0,2]x[0,0.4]x[0,0.4], E = 1e5 Pa, nu = 0 and
    0.3, clamped at x = 0, total load -1 N in z uniformly on the end face.  Quantities: mean
    u_z of the end face (exact integral of the FE field / area) and u_z at (2, 0.2, 0.2).
    Hex27 displacement elements; Euler-Bernoulli and Timoshenko values for comparison.

Every mesh level is solved from scratch; tables report the relative change to the previous
level and a Richardson extrapolation from the last three levels (refinement ratio 2).

How to run (FElupe 11.x in a separate venv, optional pypardiso for speed)::

    python3 -m venv /work/felupe-venv
    /work/felupe-venv/bin/pip install felupe pypardiso
    /work/felupe-venv/bin/python benchmarks/reference/felupe_reference.py --task cook
    /work/felupe-venv/bin/python benchmarks/reference/felupe_reference.py --task block \\
        --levels 2 4 8 16
    /work/felupe-venv/bin/python benchmarks/reference/felupe_reference.py --task all --quick

``--levels`` sets the refinement levels (Cook: elements per edge; block: elements per edge
of the modelled 0.5 x 0.5 x 0.5 (eighth) region; cantilever: elements across 0.4, 5x that
along the length).  ``--nu``, ``--element``, ``--formulation``, ``--grading`` narrow a run.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings

import numpy as np

fem = None  # felupe, imported lazily by _felupe()


def _felupe():
    global fem
    if fem is None:
        import felupe

        fem = felupe
    return fem


def _solver():
    """MKL PARDISO if installed (same results, faster), else scipy's SuperLU."""
    try:
        import pypardiso

        return pypardiso.spsolve, "pypardiso"
    except ImportError:
        from scipy.sparse.linalg import spsolve

        return spsolve, "scipy.spsolve"


def lame(mu, nu):
    return 2.0 * mu * nu / (1.0 - 2.0 * nu)


# ----------------------------------------------------------------------------------------
# materials
# ----------------------------------------------------------------------------------------


def material(energy, mu, lam, formulation):
    """Constitutive model for FElupe.

    ``tissuesim``: psi = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2 (tissuesim's neo_hookean).
      FElupe's NeoHookeCompressible(mu, lmbda) is psi = mu (tr C / 2 - ln J) + lmbda/2 (ln J)^2,
      i.e. the same law up to the constant 3 mu / 2.  Mixed: psi_hat(F) = mu (tr C/2 - ln J)
      (NeoHookeCompressible with lmbda=None) plus U(Jbar) = lam/2 (ln Jbar)^2 in the u-p-J
      functional int psi_hat(F) + U(Jbar) + p (det F - Jbar) dV (felupe.NearlyIncompressible).
    ``dealii``: psi = mu/2 (Ibar1 - 3) + kappa/4 (J^2 - 1 - 2 ln J), kappa = lam + 2 mu / 3.
    ``ogs``: psi = mu/2 (Ibar1 - 3) + K/2 (J - 1)^2, K = lam + 2 mu / 3.
    """
    f = _felupe()
    kappa = lam + 2.0 * mu / 3.0
    if formulation == "disp":
        if energy != "tissuesim":
            raise ValueError("displacement-only formulation only for the tissuesim energy")
        return f.NeoHookeCompressible(mu=mu, lmbda=lam)
    if energy == "tissuesim":
        return f.NearlyIncompressible(
            f.NeoHookeCompressible(mu=mu),
            bulk=lam,
            dUdJ=lambda J, b: b * np.log(J) / J,
            d2UdJdJ=lambda J, b: b * (1.0 - np.log(J)) / J**2,
        )
    if energy == "dealii":
        return f.NearlyIncompressible(
            f.NeoHooke(mu=mu),
            bulk=kappa,
            dUdJ=lambda J, b: 0.5 * b * (J - 1.0 / J),
            d2UdJdJ=lambda J, b: 0.5 * b * (1.0 + 1.0 / J**2),
        )
    if energy == "ogs":
        return f.NearlyIncompressible(f.NeoHooke(mu=mu), bulk=kappa)
    raise ValueError(energy)


def check_energy():
    """Check FElupe's NeoHookeCompressible against the tissuesim formula at random F."""
    f = _felupe()
    rng = np.random.default_rng(0)
    mu, lam = 1.3, 7.9
    F = np.eye(3)[:, :, None, None] + 0.2 * rng.standard_normal((3, 3, 4, 1))
    J = np.linalg.det(F.transpose(2, 3, 0, 1))
    I1 = np.einsum("ij...,ij...->...", F, F)
    psi = 0.5 * mu * (I1 - 3) - mu * np.log(J) + 0.5 * lam * np.log(J) ** 2
    W = f.NeoHookeCompressible(mu=mu, lmbda=lam).function([F, None])[0]
    return float(np.max(np.abs(W - 1.5 * mu - psi)))


# ----------------------------------------------------------------------------------------
# generic helpers
# ----------------------------------------------------------------------------------------


def simpson_weights(coords):
    """int N_i ds for quadratic 3-node segments on sorted, alternating vertex/mid nodes."""
    n = len(coords)
    if n < 3 or n % 2 == 0:
        raise ValueError("need an odd number (>= 3) of nodes on a quadratic edge")
    w = np.zeros(n)
    for k in range(0, n - 2, 2):
        L = coords[k + 2] - coords[k]
        w[k] += L / 6.0
        w[k + 1] += 4.0 * L / 6.0
        w[k + 2] += L / 6.0
    return w


def newton(items, field, dof0, dof1, ext0=None, solver=None):
    f = _felupe()
    res = f.newtonraphson(
        items=items,
        x0=field,
        dof1=dof1,
        dof0=dof0,
        ext0=ext0,
        tol=1e-8,
        maxiter=40,
        verbose=0,
        solver=solver,
        plugins=[f.LinesearchPlugin()],
    )
    return res


def richardson(values, h=None):
    """Richardson extrapolation v(h) = v_inf + C h^p from the last three levels.

    ``h`` are the mesh sizes (default: a ratio-2 sequence); the order p is solved for by
    bisection, so any refinement ratios are allowed."""
    if len(values) < 3:
        return None
    v1, v2, v3 = values[-3:]
    h1, h2, h3 = (4.0, 2.0, 1.0) if h is None else tuple(h[-3:])
    d1, d2 = v1 - v2, v2 - v3
    if d2 == 0.0:
        return {"p": math.inf, "value": v3, "err": 0.0}
    q = d1 / d2
    lo, hi = 1e-3, 12.0

    def g(p):
        return (h1**p - h2**p) / (h2**p - h3**p) - q

    if q <= 0.0 or g(lo) * g(hi) > 0.0:
        return {"p": float("nan"), "value": float("nan"), "err": abs(d2)}
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(lo) * g(mid) > 0.0 else (lo, mid)
    p = 0.5 * (lo + hi)
    ext = v3 - d2 * h3**p / (h2**p - h3**p)
    return {"p": p, "value": ext, "err": abs(ext - v3)}


def attempt(fn, *args, notes=None, label="", **kwargs):
    """Run one level; a Newton failure is reported (stderr and the table notes), not raised."""
    try:
        return fn(*args, **kwargs)
    except Exception as exc:  # felupe.NewtonConvergenceError and friends
        msg = f"{label}: FAILED ({type(exc).__name__}: {str(exc)[:160]})"
        print(msg, file=sys.stderr, flush=True)
        if notes is not None:
            notes.append(msg)
        return None


def fmt_table(rows, cols, key, level="N"):
    out = [
        "| " + " | ".join(c for c, _ in cols) + " | change vs previous |",
        "|" + "---|" * (len(cols) + 1),
    ]
    prev = None
    for r in rows:
        v = r[key]
        ch = "" if prev is None else f"{100.0 * (v - prev) / abs(v):+.4f} %"
        prev = v
        out.append("| " + " | ".join(fm.format(r[c]) for c, fm in cols) + f" | {ch} |")
    ext = richardson([r[key] for r in rows], [1.0 / r[level] for r in rows])
    if ext is not None:
        out.append("")
        out.append(
            f"Richardson (last 3 levels): observed order p = {ext['p']:.2f}, "
            f"extrapolated {key} = {ext['value']:.6g}, |extrapolated - finest| = "
            f"{ext['err']:.3g} ({100 * ext['err'] / abs(rows[-1][key]):.3f} %)"
        )
    return "\n".join(out)


# ----------------------------------------------------------------------------------------
# Cook's membrane (plane strain)
# ----------------------------------------------------------------------------------------


def grade(s, g):
    """Two-sided power grading of [0, 1] (g = 1: uniform) towards both ends."""
    if g == 1.0:
        return s
    return np.where(s < 0.5, 0.5 * (2.0 * s) ** g, 1.0 - 0.5 * (2.0 * (1.0 - s)) ** g)


def cook_mesh(N, element, g=2.0):
    """N x N cells; vertices graded, trapezoid-mapped, then straight-edge midpoints added."""
    f = _felupe()
    m = f.Rectangle(a=(0.0, 0.0), b=(1.0, 1.0), n=(N + 1, N + 1))
    xi, eta = grade(m.points[:, 0], g), grade(m.points[:, 1], g)
    x = 48.0 * xi
    y_low, y_up = 44.0 / 48.0 * x, 44.0 + 16.0 / 48.0 * x
    m = f.Mesh(np.column_stack([x, y_low + eta * (y_up - y_low)]), m.cells, m.cell_type)
    if element == "tri6":
        m = m.triangulate().add_midpoints_edges()
        region = f.RegionQuadraticTriangle(m)
    elif element == "quad9":
        m = m.add_midpoints_edges().add_midpoints_faces()
        region = f.RegionBiQuadraticQuad(m)
    else:
        raise ValueError(element)
    return m, region


def run_cook(
    N,
    mu,
    lam,
    traction,
    energy="tissuesim",
    element="quad9",
    formulation="mixed",
    g=2.0,
    steps=4,
    solver=None,
):
    f = _felupe()
    t0 = time.perf_counter()
    mesh, region = cook_mesh(N, element, g)
    if formulation == "mixed":
        field = f.FieldsMixed(region, n=3, planestrain=True)
    else:
        field = f.FieldContainer([f.FieldPlaneStrain(region, dim=2)])
    solid = f.SolidBody(material(energy, mu, lam, formulation), field)
    bounds = {"left": f.Boundary(field[0], fx=0.0)}
    dof0, dof1 = f.dof.partition(field, bounds)
    right = np.flatnonzero(np.isclose(mesh.points[:, 0], 48.0))
    right = right[np.argsort(mesh.points[right, 1])]
    w = simpson_weights(mesh.points[right, 1])
    assert abs(w.sum() - 16.0) < 1e-9
    values = np.zeros((len(right), 2))
    values[:, 1] = traction * w  # dead load, per unit reference length (thickness 1)
    load = f.PointLoad(field, right, values)
    tip = np.flatnonzero(np.isclose(mesh.points[:, 0], 48.0) & np.isclose(mesh.points[:, 1], 60.0))
    iters = 0
    for lf in np.linspace(1.0 / steps, 1.0, steps):
        load.update(lf * values)
        res = newton([solid, load], field, dof0, dof1, solver=solver)
        field = res.x
        iters += res.iterations
    u = field[0].values[tip[0]]
    return {
        "N": N,
        "cells": mesh.ncells,
        "dofs": int(np.sum(field.fieldsizes)),
        "ux": float(u[0]),
        "uy": float(u[1]),
        "iters": iters,
        "time": time.perf_counter() - t0,
    }


def run_cook_slab(N, mu, lam, traction, energy="dealii", g=2.0, steps=4, solver=None):
    """Cook's membrane as a 3D slab 1 mm thick, one Hex27 through the thickness, z free
    (only the face x = 0 is clamped): what the deal.II code-gallery program computes, see the
    results file.  Mixed u-p-J, discontinuous trilinear p and J."""
    f = _felupe()
    t0 = time.perf_counter()
    m = f.Rectangle(a=(0.0, 0.0), b=(1.0, 1.0), n=(N + 1, N + 1))
    xi, eta = grade(m.points[:, 0], g), grade(m.points[:, 1], g)
    x = 48.0 * xi
    y_low, y_up = 44.0 / 48.0 * x, 44.0 + 16.0 / 48.0 * x
    m = f.Mesh(np.column_stack([x, y_low + eta * (y_up - y_low)]), m.cells, m.cell_type)
    m = m.expand(n=2, z=1.0)
    m = m.add_midpoints_edges().add_midpoints_faces().add_midpoints_volumes()
    field = f.FieldsMixed(f.RegionTriQuadraticHexahedron(m), n=3)
    solid = f.SolidBody(material(energy, mu, lam, "mixed"), field)
    dof0, dof1 = f.dof.partition(field, {"left": f.Boundary(field[0], fx=0.0)})
    end = np.flatnonzero(np.isclose(m.points[:, 0], 48.0))
    ys = np.unique(np.round(m.points[end, 1], 10))
    zs = np.unique(np.round(m.points[end, 2], 10))
    w = (
        simpson_weights(ys)[np.searchsorted(ys, np.round(m.points[end, 1], 10))]
        * simpson_weights(zs)[np.searchsorted(zs, np.round(m.points[end, 2], 10))]
    )
    assert abs(w.sum() - 16.0) < 1e-9
    values = np.zeros((len(end), 3))
    values[:, 1] = traction * w
    load = f.PointLoad(field, end, values)
    for lf in np.linspace(1.0 / steps, 1.0, steps):
        load.update(lf * values)
        field = newton([solid, load], field, dof0, dof1, solver=solver).x
    tip = np.isclose(m.points[:, 0], 48.0) & np.isclose(m.points[:, 1], 60.0)
    tip &= np.isclose(m.points[:, 2], 0.5)  # mid-thickness node
    return {
        "N": N,
        "cells": m.ncells,
        "dofs": int(np.sum(field.fieldsizes)),
        "uy": float(field[0].values[tip][0, 1]),
        "time": time.perf_counter() - t0,
    }


COOK_MU = 80.194
COOK_T = 100.0 / 16.0


def task_cook(args, out):
    solver, _ = _solver()
    levels = args.levels or [8, 16, 32, 64, 128]
    combos = []
    for nu in args.nu or [0.3, 0.49, 0.4999]:
        for element in args.element or ["quad9", "tri6"]:
            for form in args.formulation or ["mixed", "disp"]:
                if form == "disp" and nu > 0.49:
                    continue  # displacement-only quadratic elements lock at nu -> 0.5
                combos.append((nu, element, form))
    for nu, element, form in combos:
        lam = lame(COOK_MU, nu)
        lv = levels if not (element == "tri6" or form == "disp") else levels[:-1] or levels
        if args.levels:
            lv = args.levels
        rows, notes = [], []
        for N in lv:
            r = attempt(
                run_cook,
                N,
                COOK_MU,
                lam,
                COOK_T,
                "tissuesim",
                element,
                form,
                args.grading,
                steps=args.steps,
                solver=solver,
                notes=notes,
                label=f"N={N}",
            )
            if r is None:
                continue
            rows.append(r)
            print(
                f"cook nu={nu} {element} {form} N={N}: uy={r['uy']:.6f} "
                f"dofs={r['dofs']} {r['time']:.1f}s",
                file=sys.stderr,
                flush=True,
            )
        out.append(f"\n### Cook, tissuesim neo_hookean, nu = {nu}, {element}, {form}\n")
        out.append(
            f"mu = {COOK_MU} MPa, lam = {lam:.6g} MPa, t_y = {COOK_T} MPa (total 100 N "
            f"per mm thickness), grading g = {args.grading}, {args.steps} load steps\n"
        )
        out.append(
            fmt_table(
                rows,
                [
                    ("N", "{}"),
                    ("cells", "{}"),
                    ("dofs", "{}"),
                    ("uy", "{:.6f}"),
                    ("ux", "{:.6f}"),
                    ("iters", "{}"),
                    ("time", "{:.1f}"),
                ],
                "uy",
            )
        )
        out.extend_notes(notes)


def task_cook_published(args, out):
    solver, _ = _solver()
    levels = args.levels or [8, 16, 32, 64]
    cases = [
        # label, mu, lam, traction, energy
        ("deal.II gallery params, deal.II energy", 0.4225, lame(0.4225, 0.3), 1.0 / 16.0, "dealii"),
        (
            "deal.II gallery params, tissuesim energy",
            0.4225,
            lame(0.4225, 0.3),
            1.0 / 16.0,
            "tissuesim",
        ),
        (
            "OGS params (E=240.565, nu=0.499), OGS energy",
            240.565 / 2.998,
            lame(240.565 / 2.998, 0.499),
            COOK_T,
            "ogs",
        ),
        (
            "OGS params (E=240.565, nu=0.499), tissuesim energy",
            240.565 / 2.998,
            lame(240.565 / 2.998, 0.499),
            COOK_T,
            "tissuesim",
        ),
        (
            "default params nu=0.4999, step-44/deal.II energy",
            COOK_MU,
            lame(COOK_MU, 0.4999),
            COOK_T,
            "dealii",
        ),
        (
            "default params nu=0.49, step-44/deal.II energy",
            COOK_MU,
            lame(COOK_MU, 0.49),
            COOK_T,
            "dealii",
        ),
        (
            "default params nu=0.3, step-44/deal.II energy",
            COOK_MU,
            lame(COOK_MU, 0.3),
            COOK_T,
            "dealii",
        ),
    ]
    for label, mu, lam, t, energy in cases:
        rows, notes = [], []
        for N in levels:
            r = attempt(
                run_cook,
                N,
                mu,
                lam,
                t,
                energy,
                "quad9",
                "mixed",
                args.grading,
                steps=args.steps,
                solver=solver,
                notes=notes,
                label=f"N={N}",
            )
            if r is None:
                continue
            rows.append(r)
            print(
                f"cook-published {label} N={N}: uy={r['uy']:.6f} {r['time']:.1f}s",
                file=sys.stderr,
                flush=True,
            )
        out.append(f"\n### Cook, {label}\n")
        out.append(
            f"mu = {mu:.6g} MPa, lam = {lam:.6g} MPa, t_y = {t:.6g} MPa, energy "
            f"`{energy}`, quad9 mixed, grading g = {args.grading}\n"
        )
        out.append(
            fmt_table(
                rows, [("N", "{}"), ("dofs", "{}"), ("uy", "{:.6f}"), ("time", "{:.1f}")], "uy"
            )
        )
        out.extend_notes(notes)
    for energy in ["dealii", "tissuesim"]:
        rows, notes = [], []
        for N in args.levels or [8, 16, 32]:
            r = attempt(
                run_cook_slab,
                N,
                0.4225,
                lame(0.4225, 0.3),
                1.0 / 16.0,
                energy,
                args.grading,
                steps=args.steps,
                solver=solver,
                notes=notes,
                label=f"N={N}",
            )
            if r is None:
                continue
            rows.append(r)
            print(
                f"cook-published slab {energy} N={N}: uy={r['uy']:.6f} {r['time']:.1f}s",
                file=sys.stderr,
                flush=True,
            )
        out.append(
            f"\n### Cook, deal.II gallery params, 3D slab 1 mm thick, z free, energy `{energy}`\n"
        )
        out.append(
            "mu = 0.4225 MPa, nu = 0.3, total force 1 N (t_y = 1/16 MPa), one Hex27 "
            f"through the thickness, mixed, grading g = {args.grading}, u_y at "
            "(48, 60, 0.5)\n"
        )
        out.append(
            fmt_table(
                rows, [("N", "{}"), ("dofs", "{}"), ("uy", "{:.6f}"), ("time", "{:.1f}")], "uy"
            )
        )
        out.extend_notes(notes)


# ----------------------------------------------------------------------------------------
# bonded block compression (3D)
# ----------------------------------------------------------------------------------------


def grade_one(s, g):
    """Power grading of [0, 1] towards s = 1."""
    return 1.0 - (1.0 - s) ** g


def block_mesh(n, element, model, g):
    f = _felupe()
    nz = n if model == "eighth" else 2 * n
    m = f.Cube(a=(0.0, 0.0, 0.0), b=(1.0, 1.0, 1.0), n=(n + 1, n + 1, nz + 1))
    p = m.points.copy()
    x = 0.5 + 0.5 * grade_one(p[:, 0], g)  # towards the free sides x = 1, y = 1
    y = 0.5 + 0.5 * grade_one(p[:, 1], g)
    if model == "eighth":
        z = 0.5 + 0.5 * grade_one(p[:, 2], g)  # towards the bonded top face z = 1
    else:
        z = grade(p[:, 2], g)  # towards both bonded faces
    m = f.Mesh(np.column_stack([x, y, z]), m.cells, m.cell_type)
    if element == "hex27":
        m = m.add_midpoints_edges().add_midpoints_faces().add_midpoints_volumes()
        region = f.RegionTriQuadraticHexahedron(m)
    elif element == "tet10":
        m = m.triangulate().add_midpoints_edges()
        region = f.RegionQuadraticTetra(m)
    else:
        raise ValueError(element)
    return m, region


def run_block(
    n,
    nu,
    element="hex27",
    model="eighth",
    g=1.0,
    steps=5,
    mu=1000.0,
    formulation="mixed",
    solver=None,
):
    f = _felupe()
    t0 = time.perf_counter()
    lam = lame(mu, nu)
    mesh, region = block_mesh(n, element, model, g)
    if formulation == "mixed":
        field = f.FieldsMixed(region, n=3)
    else:
        field = f.FieldContainer([f.Field(region, dim=3)])
    solid = f.SolidBody(material("tissuesim", mu, lam, formulation), field)
    u = field[0]
    bounds = {
        "symx": f.Boundary(u, fx=0.5, skip=(0, 1, 1)),
        "symy": f.Boundary(u, fy=0.5, skip=(1, 0, 1)),
        "top_xy": f.Boundary(u, fz=1.0, skip=(0, 0, 1)),
        "top_z": f.Boundary(u, fz=1.0, skip=(1, 1, 0)),
    }
    if model == "eighth":
        bounds["mid_z"] = f.Boundary(u, fz=0.5, skip=(1, 1, 0))
    else:
        bounds["bottom"] = f.Boundary(u, fz=0.0)
    dof0, dof1 = f.dof.partition(field, bounds)
    field_bc = field  # the boundaries refer to the fields of this (original) container
    iters = 0
    for lf in np.linspace(1.0 / steps, 1.0, steps):
        bounds["top_z"].update(-0.2 * lf)
        if model == "eighth":
            bounds["mid_z"].update(-0.1 * lf)
        ext0 = f.dof.apply(field_bc, bounds, dof0)
        res = newton([solid], field, dof0, dof1, ext0=ext0, solver=solver)
        field = res.x
        iters += res.iterations
    fint = solid.assemble.vector(field).toarray().ravel()
    npts = mesh.npoints
    fz = fint[: 3 * npts].reshape(npts, 3)[:, 2]
    top = np.isclose(mesh.points[:, 2], 1.0)
    Fz = 4.0 * float(np.sum(fz[top]))  # 4 x quarter of the top face
    Jmin = float(np.min(np.linalg.det(field[0].extract().transpose(2, 3, 0, 1))))
    return {
        "n": n,
        "cells": mesh.ncells,
        "dofs": int(np.sum(field.fieldsizes)),
        "Fz": Fz,
        "Jmin": Jmin,
        "iters": iters,
        "time": time.perf_counter() - t0,
    }


def task_block(args, out):
    solver, _ = _solver()
    for nu in args.nu or [0.45, 0.49]:
        for element in args.element or ["hex27"]:
            levels = args.levels or [2, 4, 8, 12 if element == "tet10" else 16]
            rows, notes = [], []
            for n in levels:
                r = attempt(
                    run_block,
                    n,
                    nu,
                    element,
                    args.block_model,
                    args.block_grading,
                    formulation=(args.formulation or ["mixed"])[0],
                    solver=solver,
                    notes=notes,
                    label=f"n={n}",
                )
                if r is None:
                    continue
                rows.append(r)
                print(
                    f"block nu={nu} {element} n={n}: Fz={r['Fz']:.6f} dofs={r['dofs']} "
                    f"{r['time']:.1f}s",
                    file=sys.stderr,
                    flush=True,
                )
            out.append(
                f"\n### Block, nu = {nu}, {element}, {args.block_model} model, "
                f"grading g = {args.block_grading}\n"
            )
            out.append(f"mu = 1000 Pa, lam = {lame(1000.0, nu):.6g} Pa, top moved -0.2 m\n")
            out.append(
                fmt_table(
                    rows,
                    [
                        ("n", "{}"),
                        ("cells", "{}"),
                        ("dofs", "{}"),
                        ("Fz", "{:.6f}"),
                        ("Jmin", "{:.4f}"),
                        ("iters", "{}"),
                        ("time", "{:.1f}"),
                    ],
                    "Fz",
                    "n",
                )
            )
            out.extend_notes(notes)


# ----------------------------------------------------------------------------------------
# linear elastic cantilever (3D)
# ----------------------------------------------------------------------------------------


def beam_theory(E=1e5, nu=0.0, L=2.0, b=0.4, h=0.4, P=1.0):
    I = b * h**3 / 12.0
    A = b * h
    G = E / (2.0 * (1.0 + nu))
    kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)  # Cowper, rectangle
    eb = P * L**3 / (3.0 * E * I)
    return {
        "euler_bernoulli": eb,
        "timoshenko": eb + P * L / (kappa * G * A),
        "timoshenko_5/6": eb + P * L / (5.0 / 6.0 * G * A),
        "kappa": kappa,
    }


def run_cantilever(n, nu, E=1e5, g=1.0, solver=None):
    """g > 1: power grading of the vertices towards the clamped face (x = 2 xi^g) and
    two-sided towards the faces y, z = 0, 0.4 (the singular clamped edges)."""
    f = _felupe()
    t0 = time.perf_counter()
    m = f.Cube(a=(0.0, 0.0, 0.0), b=(1.0, 1.0, 1.0), n=(5 * n + 1, n + 1, n + 1))
    p = m.points
    m = f.Mesh(
        np.column_stack([2.0 * p[:, 0] ** g, 0.4 * grade(p[:, 1], g), 0.4 * grade(p[:, 2], g)]),
        m.cells,
        m.cell_type,
    )
    m = m.add_midpoints_edges().add_midpoints_faces().add_midpoints_volumes()
    region = f.RegionTriQuadraticHexahedron(m)
    field = f.FieldContainer([f.Field(region, dim=3)])
    solid = f.SolidBody(f.LinearElastic(E=E, nu=nu), field)
    bounds = {"clamp": f.Boundary(field[0], fx=0.0)}
    dof0, dof1 = f.dof.partition(field, bounds)
    end = np.flatnonzero(np.isclose(m.points[:, 0], 2.0))
    ys, zs = np.unique(np.round(m.points[end, 1], 12)), np.unique(np.round(m.points[end, 2], 12))
    wy, wz = simpson_weights(ys), simpson_weights(zs)
    iy = np.searchsorted(ys, np.round(m.points[end, 1], 12))
    iz = np.searchsorted(zs, np.round(m.points[end, 2], 12))
    w = wy[iy] * wz[iz]  # int N_i dA on the end face (tensor-product quadratic faces)
    area = 0.16
    assert abs(w.sum() - area) < 1e-12
    values = np.zeros((len(end), 3))
    values[:, 2] = -1.0 / area * w  # total -1 N
    load = f.PointLoad(field, end, values)
    res = newton([solid, load], field, dof0, dof1, solver=solver)
    uz = res.x[0].values[end, 2]
    centre = np.isclose(m.points[end, 1], 0.2) & np.isclose(m.points[end, 2], 0.2)
    return {
        "n": n,
        "cells": m.ncells,
        "dofs": int(np.sum(res.x.fieldsizes)),
        "mean_uz": float(np.sum(w * uz) / area),
        "centre_uz": float(uz[centre][0]),
        "iters": res.iterations,
        "time": time.perf_counter() - t0,
    }


def task_cantilever(args, out):
    solver, _ = _solver()
    levels = args.levels or [1, 2, 4, 8]
    for nu in args.nu or [0.0, 0.3]:
        rows = []
        for n in levels:
            r = run_cantilever(n, nu, g=args.cant_grading, solver=solver)
            rows.append(r)
            print(
                f"cantilever nu={nu} n={n}: mean={r['mean_uz']:.8e} centre="
                f"{r['centre_uz']:.8e} {r['time']:.1f}s",
                file=sys.stderr,
                flush=True,
            )
        bt = beam_theory(nu=nu)
        out.append(
            f"\n### Cantilever, nu = {nu}, Hex27 (E = 1e5 Pa), grading g = {args.cant_grading}\n"
        )
        out.append(
            "Beam theory (deflection magnitude, downwards): Euler-Bernoulli "
            f"{bt['euler_bernoulli']:.6e} m; Timoshenko (Cowper kappa = "
            f"{bt['kappa']:.4f}) {bt['timoshenko']:.6e} m; Timoshenko (kappa = 5/6) "
            f"{bt['timoshenko_5/6']:.6e} m\n"
        )
        cols = [
            ("n", "{}"),
            ("cells", "{}"),
            ("dofs", "{}"),
            ("mean_uz", "{:.8e}"),
            ("centre_uz", "{:.8e}"),
            ("time", "{:.1f}"),
        ]
        out.append(fmt_table(rows, cols, "mean_uz", "n"))
        out.append("")
        out.append(fmt_table(rows, cols, "centre_uz", "n"))


# ----------------------------------------------------------------------------------------


class _Out(list):
    """Prints every table as soon as it is complete (a later failure loses nothing)."""

    def append(self, text):
        super().append(text)
        print(text, flush=True)

    def extend_notes(self, notes):
        for note in notes:
            self.append(f"\nNote: {note}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--task", default="all", choices=["cook", "cook-published", "block", "cantilever", "all"]
    )
    ap.add_argument(
        "--levels",
        type=int,
        nargs="+",
        default=None,
        help="refinement levels (see the module docstring)",
    )
    ap.add_argument("--nu", type=float, nargs="+", default=None)
    ap.add_argument(
        "--element", nargs="+", default=None, choices=["quad9", "tri6", "hex27", "tet10"]
    )
    ap.add_argument("--formulation", nargs="+", default=None, choices=["mixed", "disp"])
    ap.add_argument(
        "--grading",
        type=float,
        default=2.0,
        help="Cook: two-sided power grading exponent of the mesh (1 = uniform)",
    )
    ap.add_argument("--steps", type=int, default=4, help="Cook: number of equal load steps")
    ap.add_argument("--block-model", default="eighth", choices=["eighth", "quarter"])
    ap.add_argument(
        "--block-grading",
        type=float,
        default=1.0,
        help="block: power grading towards the bonded edges (1 = uniform)",
    )
    ap.add_argument(
        "--cant-grading",
        type=float,
        default=1.0,
        help="cantilever: power grading towards the clamped edges (1 = uniform)",
    )
    ap.add_argument("--quick", action="store_true", help="coarse levels only (smoke test)")
    args = ap.parse_args(argv)
    if args.quick and args.levels is None:
        args.levels = {
            "cook": [4, 8, 16],
            "cook-published": [4, 8, 16],
            "block": [1, 2, 4],
            "cantilever": [1, 2, 4],
        }.get(args.task, [2, 4, 8])
    warnings.simplefilter("ignore", DeprecationWarning)
    f = _felupe()
    _, solver_name = _solver()
    out = _Out()
    out.append(
        f"FElupe {f.__version__}, numpy {np.__version__}, linear solver {solver_name}, "
        f"check |psi_felupe - 3mu/2 - psi_tissuesim| = {check_energy():.2e}"
    )
    tasks = {
        "cook": task_cook,
        "cook-published": task_cook_published,
        "block": task_block,
        "cantilever": task_cantilever,
    }
    chosen = list(tasks) if args.task == "all" else [args.task]
    if args.task == "all" and args.quick:
        for name in chosen:
            sub = argparse.Namespace(**vars(args))
            sub.levels = {
                "cook": [4, 8, 16],
                "cook-published": [4, 8, 16],
                "block": [1, 2, 4],
                "cantilever": [1, 2, 4],
            }[name]
            tasks[name](sub, out)
    else:
        for name in chosen:
            tasks[name](args, out)


if __name__ == "__main__":
    main()
