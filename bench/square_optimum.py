#!/usr/bin/env python3
"""Shortest time of the benchmark square (50 x 50 mm, 1 mm corner radii, F6000) that any
control could reach on the bench machine with a jerk limit: a reference for klar's figure.

Each axis is a triple integrator with its own limits (speed 100 mm/s, acceleration
1000 mm/s^2, jerk J), sampled every millisecond with a constant jerk per period, as a servo
loop commands it. The tool must stay within the path tolerance of the programmed contour at
every sample and the path speed within the feed. One corner is solved as a linear program:
starting D mm before it at full speed along X, ending on the next edge at full speed along Y,
reaching as far along that edge as possible in a fixed time. Which part of the contour (edge,
arc, edge) each sample keeps to is taken from the previous solution, and the inner side of
the tolerance band round the arc is replaced by the tangent at the previous solution's
point; both only restrict the motion, so every solution is a motion within all limits and
its time an upper bound of the optimum. A few rounds settle it.

The square is then its two straight runs from and to rest (closed-form jerk-limited ramps),
three stretches at full speed and four such corners.

Needs numpy and scipy. Usage: bench/square_optimum.py [jerk mm/s^3] [tolerance mm]
"""
import sys

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import lil_matrix

SPEED, ACCEL = 100.0, 1000.0
RADIUS = 1.0
PERIOD = 1e-3
# Distance (mm) from the corner at which the solved stretch starts and ends at full speed.
REACH = 10.0
# Time (s) given to the solved stretch; ample for the corner.
HORIZON = 0.35
# The arc's centre; it runs from (24, 0) to (25, 1).
CX, CY = 24.0, 1.0
# Sides of the polygon inside the round speed limit that stands for it.
SIDES = 32
# Share of the tolerance the samples keep to: the path between them stays within all of it.
BAND = 0.95
ROUNDS = 12


def corner_time(jerk, tolerance):
    """Time (s) from REACH before the corner to REACH after it, at full speed on both, and
    what `verify` finds of the motion."""
    tol = BAND * tolerance
    n = int(round(HORIZON / PERIOD))
    # Variables: per sample k = 0..n: x, y, vx, vy, ax, ay; per period k < n: jx, jy as
    # shares of the jerk limit (for the solver's scaling);
    # per sample k: slack of its band constraints (kept at zero by its cost).
    def state(k, q):
        return 6 * k + q

    def jerk_of(k, q):
        return 6 * (n + 1) + 2 * k + q

    def slack(k):
        return 6 * (n + 1) + 2 * n + k

    count = 6 * (n + 1) + 3 * n + 1

    eq = lil_matrix((6 * n + 11, count))
    rhs_eq = []
    row = 0
    h = PERIOD
    for k in range(n):
        for q in range(2):
            p, v, a, j = state(k, q), state(k, 2 + q), state(k, 4 + q), jerk_of(k, q)
            # Exact integration over one period of constant jerk.
            for target, terms in (
                (state(k + 1, q), {p: 1, v: h, a: h * h / 2, j: jerk * h**3 / 6}),
                (state(k + 1, 2 + q), {v: 1, a: h, j: jerk * h * h / 2}),
                (state(k + 1, 4 + q), {a: 1, j: jerk * h}),
            ):
                eq[row, target] = 1
                for var, c in terms.items():
                    eq[row, var] = -c
                rhs_eq.append(0.0)
                row += 1
    for q, value in enumerate([CX - REACH, 0.0, SPEED, 0.0, 0.0, 0.0]):
        eq[row, state(0, q)] = 1
        rhs_eq.append(value)
        row += 1
    for q, value in [(0, CX + RADIUS), (2, 0.0), (3, SPEED), (4, 0.0), (5, 0.0)]:
        eq[row, state(n, q)] = 1
        rhs_eq.append(value)
        row += 1

    bounds = []
    for _ in range(n + 1):
        bounds += [(None, None)] * 2 + [(-SPEED, SPEED)] * 2 + [(-ACCEL, ACCEL)] * 2
    bounds += [(-1.0, 1.0)] * (2 * n)
    bounds += [(0, None)] * (n + 1)
    cost = np.zeros(count)
    cost[state(n, 1)] = -1.0
    for k in range(n + 1):
        cost[slack(k)] = 1e4

    def part(x, y):
        if x <= CX:
            return 0
        return 2 if y >= CY else 1

    # First guess: the contour at a speed that dips to 30 mm/s in the corner.
    arc = np.pi / 2 * RADIUS

    def on_contour(s):
        if s < REACH:
            return (CX - REACH + s, 0.0)
        if s < REACH + arc:
            t = -np.pi / 2 + (s - REACH) / RADIUS
            return (CX + RADIUS * np.cos(t), CY + RADIUS * np.sin(t))
        return (CX + RADIUS, CY + s - REACH - arc)

    points, s = [], 0.0
    for _ in range(n + 1):
        points.append(on_contour(s))
        s += h * min(SPEED, np.sqrt(30.0**2 + 1600.0 * max(abs(s - REACH - arc / 2) - arc / 2, 0.0)))

    best = None
    for _ in range(ROUNDS):
        rows, rhs = [], []

        def keep(terms, bound, k):
            terms = dict(terms)
            terms[slack(k)] = -1.0
            rows.append(terms)
            rhs.append(bound)

        for k, (px, py) in enumerate(points):
            for m in range(SIDES):
                # Corners of the polygon on the circle, one on each axis direction.
                t = 2 * np.pi * (m + 0.5) / SIDES
                rows.append({state(k, 2): np.cos(t), state(k, 3): np.sin(t)})
                rhs.append(SPEED * np.cos(np.pi / SIDES))
            x, y = state(k, 0), state(k, 1)
            which = part(px, py)
            if which == 0:
                keep({y: 1}, tol, k)
                keep({y: -1}, tol, k)
                keep({x: 1}, CX, k)
            elif which == 2:
                keep({x: 1}, CX + RADIUS + tol, k)
                keep({x: -1}, -(CX + RADIUS - tol), k)
                keep({y: -1}, -CY, k)
            else:
                keep({x: -1}, -CX, k)
                keep({y: 1}, CY, k)
                d = np.hypot(px - CX, py - CY)
                ux, uy = ((px - CX) / d, (py - CY) / d) if d > 1e-9 else (0.7071, -0.7071)
                # Outside the inner circle: beyond its tangent at the previous point.
                keep({x: -ux, y: -uy}, -(ux * CX + uy * CY) - (RADIUS - tol), k)
                # Inside the outer circle: within its tangents near that point.
                for m in range(-3, 4):
                    t = np.arctan2(uy, ux) + 0.15 * m
                    c, s_ = np.cos(t), np.sin(t)
                    keep({x: c, y: s_}, c * CX + s_ * CY + RADIUS + tol, k)
        ub = lil_matrix((len(rows), count))
        for i, terms in enumerate(rows):
            for var, c in terms.items():
                ub[i, var] = c
        res = linprog(
            cost,
            A_ub=ub.tocsr(),
            b_ub=np.array(rhs),
            A_eq=eq.tocsr(),
            b_eq=np.array(rhs_eq),
            bounds=bounds,
            method="highs",
        )
        if res.status != 0:
            raise RuntimeError(res.message)
        sol = res.x
        if sum(sol[slack(k)] for k in range(n + 1)) > 1e-9:
            raise RuntimeError("no motion within the band from this guess")
        points = [(sol[state(k, 0)], sol[state(k, 1)]) for k in range(n + 1)]
        reached = sol[state(n, 1)]
        best = HORIZON - (reached - (CY + REACH)) / SPEED
        jerks = [(jerk * sol[jerk_of(k, 0)], jerk * sol[jerk_of(k, 1)]) for k in range(n)]
    return best, verify(jerks)


def distance_to_contour(x, y):
    """Distance from the programmed contour near the corner: edge, arc, edge."""
    if x <= CX:
        return abs(y)
    if y >= CY:
        return abs(x - CX - RADIUS)
    return abs(np.hypot(x - CX, y - CY) - RADIUS)


def verify(jerks):
    """Integrates the jerks anew (ten points a period) and returns the largest distance
    from the contour, path speed, axis speed, acceleration and jerk."""
    x = np.array([CX - REACH, 0.0])
    v = np.array([SPEED, 0.0])
    a = np.zeros(2)
    worst = [0.0, 0.0, 0.0, 0.0, 0.0]
    for j in jerks:
        j = np.array(j)
        for i in range(1, 11):
            t = PERIOD * i / 10
            p = x + v * t + a * t * t / 2 + j * t**3 / 6
            u = v + a * t + j * t * t / 2
            worst[0] = max(worst[0], distance_to_contour(*p))
            worst[1] = max(worst[1], np.hypot(*u))
            worst[2] = max(worst[2], np.abs(u).max())
        t = PERIOD
        x, v, a = x + v * t + a * t * t / 2 + j * t**3 / 6, v + a * t + j * t * t / 2, a + j * t
        worst[3] = max(worst[3], np.abs(a).max())
        worst[4] = max(worst[4], np.abs(j).max())
    return worst


def main():
    jerk = float(sys.argv[1]) if len(sys.argv) > 1 else 1e5
    tol = float(sys.argv[2]) if len(sys.argv) > 2 else 0.01
    corner, worst = corner_time(jerk, tol)
    # From rest to full speed and back: the time at full speed plus half the ramp's time.
    ramp = SPEED / ACCEL + ACCEL / jerk
    run = (CX - REACH) / SPEED + ramp / 2
    cruise = (48.0 - 2 * REACH) / SPEED
    total = 2 * run + 3 * cruise + 4 * corner
    print(f"jerk {jerk:g} mm/s^3, tolerance {tol:g} mm")
    print(f"corner ({REACH:g} mm either side): {corner * 1000:.2f} ms")
    print(f"square: {total:.4f} s")
    print(
        "checked between samples: distance from the contour {:.4f} mm, path speed {:.2f} mm/s, "
        "axis speed {:.2f} mm/s, acceleration {:.1f} mm/s^2, jerk {:.0f} mm/s^3".format(*worst)
    )


if __name__ == "__main__":
    main()
