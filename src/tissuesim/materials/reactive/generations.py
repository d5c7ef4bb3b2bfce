"""The generations of FEBio's reactive viscoelastic bonds at a body's integration points
(``FEReactiveVEMaterialPoint``, ``FEReactiveViscoelastic.cpp``), as arrays padded to the largest
count: FEBio's lists per point, Uv[k] (the right stretch when generation k started breaking,
also the reference of generation k + 1; generation 0's reference is the identity), v[k] (the
time it started breaking), f[k] (its mass then), with the derived U_k^-1 of each generation's
reference (``uinv``), its K2 = |dev ln Uv[k]| (``k2``), the reforming bonds' reference U_r
(the last Uv, the identity before any), the time and FEBio's largest count so far (``nmax``);
with a bond recruitment (``recruitment.py``) wv[k], generation k's weight brf(X) (FEBio's
``m_wv``; 1 without), and ``et``, the trigger's scalar strain at the last accepted step.

``push`` adds a generation where it starts breaking; ``cull`` merges the two oldest where the
oldest's weight (times its wv) fell below wmin, as FEBio's ``CullGenerations``: (v, Uv, f, wv) of
the second become
the weight-averaged ones of both and the first is dropped, so the merged generation's reference
becomes the identity and the next one's the averaged stretch (FEBio's lists, kept as they are).
"""

from __future__ import annotations

import numpy as np

__all__ = ["KEYS", "new_state", "weights", "push", "cull", "right_stretch", "dev_log_norm"]

KEYS = ("uv", "uinv", "k2", "v", "f", "count", "ur", "time", "nmax", "wv", "et")
#: keys a state written before recruitment lacks, and their values then (set_state_arrays)
RECRUITMENT_KEYS = ("wv", "et")


def right_stretch(F: np.ndarray) -> np.ndarray:
    """U = sqrt(F^T F) of F (..., d, d)."""
    w, v = np.linalg.eigh(np.swapaxes(F, -1, -2) @ F)
    return np.einsum("...ik,...k,...jk->...ij", v, np.sqrt(np.maximum(w, 0.0)), v)


def dev_log_norm(U: np.ndarray) -> np.ndarray:
    """|dev ln U| (Frobenius) of symmetric positive U (..., d, d), as plane strain in 2D."""
    w = np.linalg.eigvalsh(U)
    h = np.log(w)
    if U.shape[-1] == 2:
        h = np.concatenate([h, np.zeros((*h.shape[:-1], 1))], axis=-1)
    return np.sqrt(np.sum((h - h.mean(axis=-1, keepdims=True)) ** 2, axis=-1))


def new_state(n: int, d: int) -> dict[str, np.ndarray]:
    """No generations at n points."""
    return {
        "uv": np.zeros((n, 0, d, d)), "uinv": np.zeros((n, 0, d, d)), "k2": np.zeros((n, 0)),
        "v": np.zeros((n, 0)), "f": np.zeros((n, 0)), "count": np.zeros(n),
        "ur": np.broadcast_to(np.eye(d), (n, d, d)).copy(), "time": np.zeros(1),
        "nmax": np.zeros(1), "wv": np.zeros((n, 0)), "et": np.zeros(n),
    }  # fmt: skip


def weights(
    s: dict, relaxation, kinetics: int, t: float, k2_new: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(w (n, G) of the breaking generations at time t, the reforming bonds' weight (n,)).

    Type I: w_k = f_k g(t - v_k; K2_k), reforming 1 - sum w_k. Type II, as FEBio's
    ``BreakingBondMassFraction`` (which sets F to Uv[k] for both terms): w_k = g(t - v_k; K2_k)
    - g(t - v_(k-1); K2_k), and the reforming generation (FEBio's newest, v = t) weighs
    1 - g(t - v_last; K2) at its own K2 (``k2_new``, FEBio's current stretch; default the
    last generation's), 1 before any generation. The type II weights need not sum to 1."""
    G = s["v"].shape[1]
    live = np.arange(G)[None, :] < s["count"][:, None]
    g = np.where(live, relaxation(np.where(live, t - s["v"], 0.0), s["k2"]), 0.0)
    if kinetics == 1:
        w = s["f"] * g
        return w, 1.0 - w.sum(axis=1)
    w = g.copy()
    if G > 1:
        later = live[:, 1:]
        dt = np.where(later, t - s["v"][:, :-1], 0.0)
        w[:, 1:] -= np.where(later, relaxation(dt, s["k2"][:, 1:]), 0.0)
    n = s["count"].shape[0]
    last = np.maximum(s["count"].astype(int) - 1, 0)
    if k2_new is None:
        k2_new = s["k2"][np.arange(n), last] if G else np.zeros(n)
    v_last = s["v"][np.arange(n), last] if G else np.zeros(n)
    g_last = relaxation(np.maximum(t - v_last, 0.0), k2_new)
    return w, np.where(s["count"] > 0, 1.0 - g_last, 1.0)


def _derive(s: dict, idx: np.ndarray) -> None:
    """uinv, k2 and ur of points idx from their uv and count."""
    d = s["ur"].shape[-1]
    G = s["uv"].shape[1]
    eye = np.eye(d)
    for p in idx:
        c = int(s["count"][p])
        s["uinv"][p] = 0.0
        if c:
            s["uinv"][p, 0] = eye
            if c > 1:
                s["uinv"][p, 1:c] = np.linalg.inv(s["uv"][p, : c - 1])
            s["k2"][p, :c] = dev_log_norm(s["uv"][p, :c])
        s["k2"][p, c:G] = 0.0
        s["ur"][p] = s["uv"][p, c - 1] if c else eye


def push(
    s: dict, idx: np.ndarray, U: np.ndarray, t: float, fr: np.ndarray, wv: np.ndarray | None = None
) -> None:
    """Generation (reference U_r, start t, mass fr, recruitment weight wv: default 1) at points
    idx; U_r becomes U (len(idx),)."""
    if idx.size == 0:
        return
    c = s["count"][idx].astype(int)
    if (c >= s["v"].shape[1]).any():  # one more slot for every point
        for key in ("uv", "uinv", "k2", "v", "f", "wv"):
            more = np.zeros((s[key].shape[0], 1, *s[key].shape[2:]))
            s[key] = np.concatenate([s[key], more], axis=1)
    s["uv"][idx, c] = U
    s["v"][idx, c] = t
    s["f"][idx, c] = fr
    s["wv"][idx, c] = 1.0 if wv is None else wv
    s["count"][idx] += 1
    _derive(s, idx)


def cull(s: dict, idx: np.ndarray, relaxation, kinetics: int, t: float, wmin: float) -> None:
    """FEBio's culling at the points idx that just got a generation: with at least three
    generations and as many as FEBio's largest count so far, the oldest two merge when the
    oldest's weight is below wmin (then the newest's mass is recomputed, as FEBio does)."""
    if idx.size == 0:
        return
    s["nmax"] = np.array([max(float(s["nmax"][0]), float(s["count"][idx].max()))])
    c = s["count"][idx]
    idx = idx[(c >= 3) & (c >= s["nmax"][0])]
    if idx.size == 0 or wmin <= 0.0:
        return
    w, _ = weights(s, relaxation, kinetics, t)
    w = w * s["wv"]  # FEBio weighs by the recruitment here
    merge = idx[w[idx, 0] < wmin]
    for p in merge:
        w0, w1 = w[p, 0], w[p, 1]
        for key in ("v", "f", "uv", "wv"):
            s[key][p, 1] = (w0 * s[key][p, 0] + w1 * s[key][p, 1]) / (w0 + w1)
            s[key][p, :-1] = s[key][p, 1:].copy()
            s[key][p, -1] = 0.0
        s["count"][p] -= 1
    _derive(s, merge)
    if merge.size:  # the newest generation's mass, from the culled list
        last = s["count"][merge].astype(int) - 1
        s["f"][merge, last] = 0.0
        w, _ = weights(s, relaxation, kinetics, t)
        if kinetics == 1:
            s["f"][merge, last] = 1.0 - w[merge].sum(axis=1)
        _derive(s, merge)
