"""What a ``Simulation`` checks before stepping and reports after a step (a mixin): a
quasistatic solve must be held, explicit steps must be below the stability limit; the step's
contact figures, the explicit steps' reactions and the tissue's topology events."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from tissuesim.contact.readout.indentation import is_probe
from tissuesim.errors import InputError

__all__ = ["StepChecks", "STABILITY_MARGIN"]

#: explicit time steps above this multiple of the stability estimate are refused
STABILITY_MARGIN = 1.5


class StepChecks:
    """Mixed into ``Simulation``."""

    def _check_supported(self) -> bool:
        """A quasistatic solve that nothing holds has no solution (SciPy would return finite
        garbage): refuse it, unless contact can hold the bodies; returns whether the step must
        then come to rest in pseudo-time (``time/integrators/pseudo_time.py``)."""
        held_by_contact = self._held_by_contact()
        if held_by_contact and not self.system.contact.has_friction:
            raise InputError(
                "a quasistatic body held only by contact needs friction: without it, it is "
                "free to slide and turn on what it rests on, and its equilibrium is not unique "
                "(the solve drifts); give the contact a friction > 0 ([contact] friction), "
                "supports (fix), or use backward_euler"
            )
        return held_by_contact

    def _held_by_contact(self) -> bool:
        from tissuesim.time.integrators.quasistatic import check_supported

        s = self.system
        if len(s.bodies) == 1 and self._active()[0].kind == "fem":
            try:
                check_supported(s.bodies[0])
            except InputError as exc:
                if s.contact is None:
                    raise InputError(
                        f"{exc} A body that rests on an obstacle or another body is held by "
                        "contact: set_contact(...) ([contact]) with friction makes it come to "
                        "rest there."
                    ) from None
                return True
            self._warn_free_translations(self._active()[0])
            return False
        springs = any(b.kind == "frames" and b.model.springs for b in self._active())
        spring_graspers = any(b.kind == "fem" and b.spring_graspers for b in self._active())
        if s.contact is not None and not (s.ties or s.attachments):
            for b in self._active():
                if b.kind == "fem" and not b.spring_graspers:
                    try:
                        check_supported(b.model)
                    except InputError:
                        return True  # a free body: contact must hold it
        if not (s.prescribed_dofs.size or springs or spring_graspers):
            if s.contact is not None:
                return True
            raise InputError(
                "a quasistatic solve needs supports, fixed or prescribed frames, or springs, to "
                "hold the bodies against rigid motions; add fix(...) / fix_frames(...), contact "
                "with something they rest on (set_contact), or use backward_euler"
            )
        return False

    _free_translations_checked = None  # the system whose free translations were looked for

    def _warn_free_translations(self, body: Any) -> None:
        """A lone body that no condition holds along an axis (a biaxial test holding x and y
        and leaving z free: FEBio's ma57) has a family of equilibria shifted along that axis,
        and a quasistatic solve ends at one of them, wherever its factorisation puts the
        shift (FEBio's too, at a zero pivot): said once, as the answer depends on it."""
        s = self.system
        if self._free_translations_checked is s:
            return
        self._free_translations_checked = s
        held_otherwise = (
            s.contact is not None
            or s.rigid
            or s.ties
            or s.attachments
            or body.springs
            or body.spring_graspers
            or body.linear_constraints
        )
        if held_otherwise:
            return
        d = body.model.mesh.dim
        held = set((body.model.prescribed.dofs % d).tolist())
        free = [k for k in range(d) if k not in held]
        if free:
            axes = " and ".join("xyz"[k] for k in free)
            warnings.warn(
                f"body {body.name!r}: no condition holds it along {axes}, so its quasistatic "
                f"equilibria are a family shifted along {axes} and the solve ends at one of "
                f"them, where its factorisation puts the shift; hold one vertex's {axes} "
                "component ([[dirichlet]] components) for a unique answer",
                UserWarning,
                stacklevel=4,
            )

    _stability_checked = None  # the system whose explicit stability limit was checked

    def _check_stability(self) -> None:
        """Explicit steps far above the stability limit blow up: refuse them before the first
        step. The estimate is within 21 % of the true limit 2 / omega_max on the test meshes
        (benchmarks/results/explicit_limit.md), so above STABILITY_MARGIN times it no run is
        stable; between 1 and that a warning, and the blow-up check of each step stands."""
        limit = self.critical_time_step()
        h = self.time_step
        if h > STABILITY_MARGIN * limit:
            raise InputError(
                f"time_step {h:g} s is {h / limit:.3g} x the explicit stability limit (estimate "
                f"{limit:.3g} s); explicit steps would blow up: use time_step <= "
                f"{0.9 * limit:.3g} s, or integrator = backward_euler"
            )
        if h > limit:
            warnings.warn(
                f"time_step {h:g} s is above the explicit stability estimate {limit:.3g} s; the "
                "run stops if the energy grows without bound",
                UserWarning,
                stacklevel=3,
            )

    _contact_start_checked = False  # the contact start is checked once, before the first step

    def _check_contact_start(self) -> None:
        """Before the first step with contact: a dhat the bodies' edges cannot hold (the run
        crawled: 0 steps in 300 s), and a start that intersects (a probe inside the organ failed
        after six halvings as "did not converge ... try a smaller time_step") are refused."""
        contact = self.system.contact
        if contact is None or self._contact_start_checked:
            return
        self._check_dhat(contact)
        self._check_start_apart(contact)
        self._contact_start_checked = True

    def _check_dhat(self, contact) -> None:
        """dhat must be below the median boundary edge of every FEM body in contact: larger,
        the barrier acts between most of a body's surface at rest and the steps barely move."""
        if self.contact.dhat is None:
            return  # the default, 1e-3 of the scene's size
        from tissuesim.simulation.interactions import _median_boundary_edge

        dhat = float(contact.dhat)
        for body in self._active():
            if body.kind != "fem" or body.name not in contact.slices:
                continue
            edge = _median_boundary_edge(body.mesh)
            if dhat < edge:
                continue
            extent = " x ".join(f"{v:.3g}" for v in np.ptp(body.mesh.points, axis=0))
            diagonal = float(np.linalg.norm(np.ptp(contact.rest, axis=0)))
            suggested = float(f"{min(1e-3 * diagonal, 0.1 * edge):.1g}")
            raise InputError(
                f"contact dhat = {dhat:g} m is not below the edges of body {body.name!r} "
                f"({extent} m, boundary edges {edge:.3g} m median): the barrier would act "
                f"across its surface at rest; use dhat = {suggested:g} m or less ([contact] "
                "dhat, set_contact(dhat=...)), or leave it out (1e-3 of the scene's size)"
            )

    def _check_start_apart(self, contact) -> None:
        """The bodies and obstacles must start apart: name the first pair that intersects."""
        x, t = self._state.x, self.time
        if not contact.intersecting(x, t):
            return
        import ipctk

        names = list(contact.table.names)  # the bodies' surfaces, then the obstacles
        n_bodies = len(contact.surfaces)
        V = contact.vertices(x, t)
        for i in range(n_bodies):
            for j in range(i, len(names)):
                if not contact.table.enabled[i, j]:
                    continue
                rest = np.asfortranarray(contact.rest)
                mesh = ipctk.CollisionMesh(rest, contact.mesh.edges, contact.mesh.faces)
                if i == j:  # the body with itself
                    mesh.can_collide = ~_not_in(ipctk, contact.group, i)
                else:
                    mesh.can_collide = contact.table.pair_filter(ipctk, contact.group, i, j)
                if not ipctk.has_intersections(mesh, V):
                    continue
                what = f"obstacle {names[j]!r}" if j >= n_bodies else f"body {names[j]!r}"
                if i == j:
                    said = f"body {names[i]!r} intersects itself"
                else:
                    said = f"{what} intersects body {names[i]!r}"
                raise InputError(
                    f"{said} at t = {t:g} s, before the first step: contact keeps surfaces "
                    "apart and cannot separate ones that start crossed; move them apart (an "
                    "obstacle's translation at the start, the meshes' placement)"
                )
        raise InputError(
            f"the contact surfaces intersect at t = {t:g} s, before the first step: contact "
            "keeps surfaces apart and cannot separate ones that start crossed; move them apart"
        )

    def _contact_report(self, contact, x: np.ndarray, forces: dict) -> dict[str, Any]:
        """The step's contact figures, and the time split since the last report."""
        stats = contact.stats
        depths = {}
        if any(is_probe(ob) for ob in contact.obstacles):  # the bodies' vertices only then
            n = contact.n_deformable
            bodies, rest = contact.vertices(x)[:n], contact.rest[:n]
            depths = self._indentation.depths(contact.obstacles, bodies, rest, self.time, forces)
        distance, pairs = contact.proximity(x)
        report = {
            "min_distance": distance,
            "active_pairs": pairs,
            "candidates_and_barrier_s": stats.candidates_and_barrier_s,
            "candidates_s": stats.candidates_s,
            "ccd_s": stats.ccd_s,
            "barrier_evaluations": stats.evaluations,
            "ccd_calls": stats.ccd_calls,
            "friction_solves": stats.friction_solves,
            "stiffness_Pa": contact.kappa,
            "indentation_depth": depths,
            # the contact predictor's figures for the step (time/contact_step.py), or None
            "prediction": contact.prediction_report,
        }
        contact.reset_stats()
        return report

    def _static_gradient(self) -> np.ndarray | None:
        """Explicit steps have no Newton gradient: the reactions come from the static balance
        at the new state (one gradient evaluation, only when there are forces to report)."""
        if not self._force_names:
            return None
        s = self.system
        energies = self.step_energies(self.time, None, self.time_step)
        return s.evaluate(self._state.x, 1, False, energies).gradient

    def _tissue_step(self, t0: float) -> dict[str, Any]:
        tissue = self.tissue
        events = []
        if tissue.model is not None:
            j = self.system.index(tissue.name)
            z = self.system.body_config(self._state.x, j)

            def rebuild() -> np.ndarray | None:
                self._build()
                if tissue.model is None:  # all of it torn or cut: no longer in the system
                    return None
                return self.system.body_config(self._state.x, self.system.index(tissue.name))

            events = tissue.topology(z, t0, self.time, rebuild)
            if tissue.model is None:  # all tissue gone: the organs go on alone
                self._build()
        return {
            "attachment_gap": self.attachment_gap() if tissue.model is not None else 0.0,
            "tissue_points": int(tissue.dissection.alive.sum()),
            "attachments": int(sum(a.n for a in self.system.attachments)),
            "events": events,
        }


def _not_in(ipctk, group: np.ndarray, i: int):
    """An ipctk CollisionFilter accepting a vertex pair unless both are in group i (its
    complement: both in group i, a body's pairs with itself)."""
    from tissuesim.contact.pairs import _not_both_in

    return _not_both_in(ipctk, group, [i])
