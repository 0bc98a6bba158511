#!/usr/bin/env python3
"""Klartext programs that look like CAM output, for the planner's benchmarks.

They imitate what post-processors print, not any particular program: coordinates rounded to
3 decimals, the feed reduced on a short stretch split off a line just before a corner, arcs
as CC/C in the XY, XZ and YZ planes, helical entries, stepovers between passes.

  cam_style.py KIND [--passes N] > PROG.h

KIND:
  contour    2D contour at four depths: lines with rounded corner arcs, each corner
             approached by a reduced-feed stretch (F250 after F1000), helical entry
  pocket     adaptive-style clearing: trochoidal loops of 3-decimal chords along a slot,
             feed changes where the loop turns into the cut
  parallel   parallel finishing of a ball-nose surface: dense 3-decimal lines in XZ, with
             arcs in XZ and YZ at the ends of the passes and stepovers at a lower feed
  long       a long 3-axis program (the test-run benchmark): all of the above repeated
             `--passes` times (default 40: about 70,000 lines)

Every program starts with L Z+5 FMAX and ends with END PGM; the bench machine's travel
(±500 mm) holds all of them.
"""
import math
import sys


class Out:
    def __init__(self, name):
        self.name = name
        self.lines = [f"BEGIN PGM {name} MM"]
        self.feed = None

    def add(self, text):
        self.lines.append(text)

    def l(self, feed=None, **axes):
        words = " ".join(f"{k}{v:+.3f}" for k, v in axes.items())
        f = ""
        if feed == "MAX":
            f = " FMAX"
            self.feed = None
        elif feed is not None and feed != self.feed:
            f = f" F{feed:g}"
            self.feed = feed
        self.add(f"L {words}{f}")

    def cc(self, **axes):
        self.add("CC " + " ".join(f"{k}{v:+.3f}" for k, v in axes.items()))

    def c(self, dr, feed=None, **axes):
        words = " ".join(f"{k}{v:+.3f}" for k, v in axes.items())
        f = ""
        if feed is not None and feed != self.feed:
            f = f" F{feed:g}"
            self.feed = feed
        self.add(f"C {words} DR{dr}{f}")

    def text(self):
        body = self.lines + [f"END PGM {self.name} MM"]
        return "\n".join(f"{i} {t}" for i, t in enumerate(body)) + "\n"


def helix_entry(o, x, y, z_top, z_bottom, r=2.0, pitch=1.0, feed=600):
    """A helical entry at (x, y) from z_top down to z_bottom, ending at (x + r, y)."""
    o.l("MAX", Z=z_top)
    o.l("MAX", X=x + r, Y=y)
    o.cc(X=x, Y=y)
    z, turns = z_top, max(1, math.ceil((z_top - z_bottom) / pitch))
    step = (z_top - z_bottom) / turns
    for _ in range(turns):
        # Klartext helix: CP with IPA and the Z increment.
        z -= step
        o.add(f"CP IPA+360 IZ{-step:+.3f} DR+" + (f" F{feed:g}" if o.feed != feed else ""))
        o.feed = feed
    o.add(f"CP IPA+360 DR+")


def contour(o, depths=(-2.0, -4.0, -6.0, -8.0), ox=0.0, oy=0.0):
    """A 2D contour round a 120 x 80 rectangle with R6 corners, each corner approached by a
    2 mm reduced-feed stretch and left at the full feed."""
    w, h, r = 60.0, 40.0, 6.0
    fast, slow = 1000, 250
    for z in depths:
        helix_entry(o, ox - w - 10.0, oy, 5.0, z, r=2.0)
        o.l(fast, X=ox - w, Y=oy)
        corners = [
            # (line end before the corner, centre, corner end)
            ((ox - w, oy + h - r), (ox - w + r, oy + h - r), (ox - w + r, oy + h)),
            ((ox + w - r, oy + h), (ox + w - r, oy + h - r), (ox + w, oy + h - r)),
            ((ox + w, oy - h + r), (ox + w - r, oy - h + r), (ox + w - r, oy - h)),
            ((ox - w + r, oy - h), (ox - w + r, oy - h + r), (ox - w, oy - h + r)),
        ]
        x, y = ox - w, oy
        for (ex, ey), (cx, cy), (tx, ty) in corners:
            dx, dy = ex - x, ey - y
            n = math.hypot(dx, dy)
            # The reduced-feed split 2 mm before the corner, off the line by the rounding.
            sx, sy = ex - 2.0 * dx / n + 0.0004, ey - 2.0 * dy / n + 0.0004
            o.l(fast, X=sx, Y=sy)
            o.l(slow, X=ex, Y=ey)
            o.cc(X=cx, Y=cy)
            o.c("-", slow, X=tx, Y=ty)
            x, y = tx, ty
        o.l(fast, X=ox - w, Y=oy)
        o.l("MAX", Z=5.0)


def pocket(o, ox=0.0, oy=0.0, length=60.0, loops=120):
    """Adaptive-style clearing: trochoidal loops of 0.3 mm chords advancing 0.5 mm each,
    the cutting half at F1800, the return half at F3000."""
    helix_entry(o, ox, oy, 5.0, -5.0, r=3.0)
    r = 4.0
    for k in range(loops):
        cx = ox + k * length / loops
        n = int(2 * math.pi * r / 0.3)
        for i in range(1, n + 1):
            phi = 2 * math.pi * i / n
            feed = 1800 if phi < math.pi else 3000
            o.l(feed, X=cx + r * math.cos(phi) + 0.5 * i / n, Y=oy + r * math.sin(phi))
    o.l("MAX", Z=5.0)


def parallel(o, ox=0.0, oy=0.0, passes=40):
    """Parallel finishing of a ball-nose surface z = 3 cos(x/10) cos(y/15) - 8 over
    60 x 40 mm: passes along X in 0.25 mm chords (3 decimals), turned round by arcs in YZ
    at the ends, with the stepover at F400."""
    def z(x, y):
        return 3.0 * math.cos(x / 10.0) * math.cos(y / 15.0) - 8.0

    o.l("MAX", X=ox - 30.0, Y=oy - 20.0)
    o.l("MAX", Z=z(-30.0, -20.0) + 1.0)
    o.l(400, Z=z(-30.0, -20.0))
    step = 40.0 / passes
    for p in range(passes):
        y = -20.0 + p * step
        xs = [-30.0 + 0.25 * i for i in range(241)]
        if p % 2:
            xs.reverse()
        for x in xs:
            o.l(2400, X=ox + x, Y=oy + y, Z=z(x, y))
        if p + 1 == passes:
            break
        # Over to the next pass: up and over by an arc in YZ, then down at F400.
        x_end = xs[-1]
        y2 = y + step
        top = max(z(x_end, y), z(x_end, y2)) + 0.5 * step
        o.l(400, Z=top)
        o.cc(Y=oy + y + 0.5 * step, Z=top)
        o.c("-", 400, Y=oy + y2, Z=top)
        o.l(400, Z=z(x_end, y2))
    # A quarter arc in XZ out of the last pass, up and away from the surface.
    x_end, y_end = xs[-1], -20.0 + (passes - 1) * step
    side = 1.0 if x_end > 0 else -1.0
    z_end = z(x_end, y_end)
    o.cc(X=ox + x_end + 2.0 * side, Z=z_end)
    o.c("-" if side > 0 else "+", o.feed, X=ox + x_end + 2.0 * side, Z=z_end + 2.0)
    o.l("MAX", Z=5.0)


def main():
    args = sys.argv[1:]
    if not args:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    kind = args[0]
    passes = int(args[args.index("--passes") + 1]) if "--passes" in args else None
    o = Out(f"CAM_{kind.upper()}")
    o.l("MAX", Z=5.0)
    if kind == "contour":
        contour(o)
    elif kind == "pocket":
        pocket(o)
    elif kind == "parallel":
        parallel(o, passes=passes or 40)
    elif kind == "long":
        for k in range(passes or 40):
            ox = -200.0 + (k % 5) * 100.0
            oy = -200.0 + (k // 5 % 5) * 100.0
            contour(o, ox=ox, oy=oy)
            pocket(o, ox=ox - 30.0, oy=oy, loops=60)
            parallel(o, ox=ox, oy=oy, passes=20)
    else:
        print(f"unknown kind {kind}", file=sys.stderr)
        sys.exit(2)
    o.l("MAX", Z=5.0)
    sys.stdout.write(o.text())


if __name__ == "__main__":
    main()
