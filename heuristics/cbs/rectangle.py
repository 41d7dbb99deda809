"""Rectangle reasoning for point robots on a 4-connected grid (classic collisions).

Two robots that cross an open area at right angles meet in one cell, and each of the many
equally short ways of either to get around the other leads to the same meeting one cell further
on: splitting on the vertex again and again explores all of them. The *rectangle* split (Li,
Gange, Harabor, Stuckey, Ma, Koenig 2019; the R variant, anchored at the starts) ends this in one
branch per robot. Which split is used is decided in :mod:`.search`; this module finds the
rectangle and proves the split complete.

Set-up. Cells are ``(x, y)``; a move changes one coordinate by one or waits. Flip the axes so that
both starts ``s1, s2`` are at or below the conflict cell ``c`` in both coordinates (no flip
exists when one start is on each side of ``c``: no rectangle). The conflict is at time
``t = |c - s1| = |c - s2|`` (``|.|`` the Manhattan length): both robots came straight. Let robot 1
be the one of smaller ``x`` start; then ``Rs = (s2.x, s1.y)`` (``s1.x < s2.x`` and ``s1.y > s2.y``:
equal distances to ``c`` from distinct starts in one quadrant). The rectangle is ``R = [Rs.x, X1] x
[Rs.y, Y1]`` for any ``X1 >= c.x``, ``Y1 >= c.y``. For a cell ``z`` of ``R``,
``|z - s1| = |z - Rs| + |Rs - s1|``, and ``|Rs - s1| = |Rs - s2|`` (both are ``t - |c - Rs|``):

    (T) both robots need the same least time ``|z - s1| = |z - s2|`` to reach any cell of ``R``.

The barriers: ``B1`` = the cells ``(X1, y)``, ``Rs.y <= y <= Y1`` (``R``'s far column), each at time
``|b - s1|``; ``B2`` = the cells ``(x, Y1)``, ``Rs.x <= x <= X1`` (its far row), each at ``|b - s2|``.
Branches: robot 1 is at no cell of ``B1`` at its time; or robot 2 at no cell of ``B2`` at its time.

Complete (every schedule without a conflict between the two keeps one branch). Suppose path
``p1`` is at ``b1 in B1`` at time ``|b1 - s1|`` and ``p2`` at ``b2 in B2`` at ``|b2 - s2|``. A walk
that covers a Manhattan length in as many steps never waits nor turns back, so ``p1`` up to ``b1``
is monotone: ``y`` runs from ``Rs.y`` to ``b1.y <= Y1`` and ``x`` from ``s1.x < Rs.x`` to ``X1``; from
the first time it reaches column ``Rs.x`` it is inside ``R`` and it crosses ``R`` from its first
column to its last. Likewise ``p2`` crosses ``R`` from its first row to its last. Such a crossing
``A`` holds, in each column ``x``, a run of rows ``[lo(x), hi(x)]`` with ``lo(x + 1) = hi(x)``. ``p2``
starts in ``R`` on ``A`` or below it (row ``Rs.y <= lo``) and ends on ``A`` or above it (row ``Y1 >= hi``);
from below ``A`` a step up lands at most on ``lo(x)``, a step right stays below (``lo(x + 1) >=
lo(x)``), so ``p2`` cannot get above without standing on a cell ``z`` of ``A``. Both paths are
monotone from their starts, so ``p1`` is on ``z`` at time ``|z - s1|`` and ``p2`` at ``|z - s2|``:
the same time by (T), a vertex conflict.

Both branches exclude the current paths when each is on its barrier at its time: the smallest
rectangle (``X1 = c.x``, ``Y1 = c.y``) always qualifies, since ``c`` is on both barriers. Larger
ones, from the goals, are kept where the current paths qualify too; among them, the one whose
barriers the most of the two robots' shortest paths all cross (by their MDDs: the branch then
raises that robot's cost) is chosen.
"""
from __future__ import annotations

from .constraints import VERTEX
from .lowlevel import MDD, Path, meets_all

RECTANGLE = 4  # a conflict kind, after those of :mod:`.conflicts`


def rectangle(conflict, paths: list[Path], mdds: tuple[MDD | None, MDD | None], goals: tuple[int, int],
              width: int):
    """The best rectangle split of a vertex ``conflict`` as ``((RECTANGLE, r1, r2, t, (B1, B2)),
    score)``, ``B1``/``B2`` tuples of VERTEX constraints and ``score`` how many of the two branches
    raise a cost (0-2); None if the conflict is not a rectangle's (module docstring)."""
    _, i, j, t, c = conflict
    pi, pj = paths[i], paths[j]
    si, sj = pi.poses[0], pj.poses[0]
    cx, cy = c % width, c // width
    flip = []
    for a, b, m in ((si % width, sj % width, cx), (si // width, sj // width, cy)):
        if a <= m and b <= m:
            flip.append(1)
        elif a >= m and b >= m:
            flip.append(-1)
        else:
            return None
    fx, fy = flip

    def frame(cell: int) -> tuple[int, int]:
        return fx * (cell % width), fy * (cell // width)

    def cell(u: int, v: int) -> int:
        return fy * v * width + fx * u

    (ux, uy), (vx, vy), (cu, cv) = frame(si), frame(sj), frame(c)
    if (cu - ux) + (cv - uy) != t or (cu - vx) + (cv - vy) != t or (ux, uy) == (vx, vy):
        return None
    if ux > vx:  # robot 1 comes from the smaller x
        i, j, pi, pj, (ux, uy), (vx, vy) = j, i, pj, pi, (vx, vy), (ux, uy)
        mdds, goals = mdds[::-1], goals[::-1]
    x0, y0 = vx, uy  # Rs
    g1, g2 = (frame(g) if g >= 0 else (cu, cv) for g in goals)
    best = None
    for x1 in sorted({cu, max(cu, min(g1[0], g2[0])), max(cu, g1[0])}):
        for y1 in sorted({cv, max(cv, min(g1[1], g2[1])), max(cv, g2[1])}):
            b1 = tuple((VERTEX, cell(x1, y), (x1 - ux) + (y - uy)) for y in range(y0, y1 + 1))
            b2 = tuple((VERTEX, cell(x, y1), (x - vx) + (y1 - vy)) for x in range(x0, x1 + 1))
            if not (_on(pi, b1) and _on(pj, b2)):
                continue
            score = meets_all(mdds[0], b1) + meets_all(mdds[1], b2)
            key = (score, (x1 - x0 + 1) * (y1 - y0 + 1))
            if best is None or key > best[0]:
                best = (key, (RECTANGLE, i, j, t, (b1, b2)))
    return None if best is None else (best[1], best[0][0])


def _on(path: Path, barrier: tuple) -> bool:
    """Whether ``path`` is on a cell of ``barrier`` at its time."""
    last = len(path.poses) - 1
    return any(path.poses[min(time, last)] == b for _, b, time in barrier)
