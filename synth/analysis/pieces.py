"""A turn's pieces on which a design's loads are smooth (``loads``): each with its own numbers
(the load's segment, the guide's friction's sign), evaluated together; their quantities on a
grid, their roots (stationary points, crossings) polished to machine precision, and their
integrals by adaptive Gauss–Legendre quadrature."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .forces import Forces, Torques
from .model import GRID, Polisher
from .roots import TWO_PI, polish, rtsafe

# the quadrature: 16-point Gauss–Legendre on panels at most PANEL wide, each halved (at most
# HALVINGS times) until the 8-point rule agrees with it to AGREE × the turn's largest |T|
# (|T|² for ∫ T²) × its width: the 16-point rule is then exact to rounding
PANEL, HALVINGS, AGREE = math.pi / 8, 7, 1e-14
RULE, CHECK = np.polynomial.legendre.leggauss(16), np.polynomial.legendre.leggauss(8)


# a quantity of z, z′, z″ (rows: angles): its value and first two derivatives at each angle
Quantity = Callable[[np.ndarray], np.ndarray]
Found = tuple[np.ndarray, np.ndarray]  # angles (radians) and the piece or value at each


@dataclass(frozen=True)
class Piece:
    """A part [lo, hi] of the turn (radians) where the load is one (``pv``: the design's and
    the load's numbers, ``kinetics.LOAD``) and everything is smooth; ``span``: which of the
    turn's spans (``loads``') it lies in."""

    lo: float
    hi: float
    pv: np.ndarray
    span: int


class Pieces:
    """Pieces evaluated together, each angle with its piece's numbers: their quantities on a
    grid (``GRID`` cells a turn, at least 8 a piece), their roots, their integrals."""

    def __init__(self, sys: Forces | Torques, pieces: list[Piece]) -> None:
        self.sys, self.pieces = sys, pieces
        self.lo = np.array([p.lo for p in pieces])
        self.hi = np.array([p.hi for p in pieces])
        self.pv = np.array([p.pv for p in pieces])
        cells = np.maximum(8, np.ceil(GRID * (self.hi - self.lo) / TWO_PI).astype(int))
        spans = zip(self.lo, self.hi, cells, strict=True)
        self.grid = np.concatenate([np.linspace(a, b, c + 1) for a, b, c in spans])
        self.owner = np.repeat(np.arange(len(pieces)), cells + 1)
        self.starts = np.concatenate([[0], np.cumsum(cells + 1)[:-1]])  # each piece's first
        self.cells = np.nonzero(self.owner[:-1] == self.owner[1:])[0]  # grid[i] to grid[i + 1]
        self.z = sys(self.grid, self.pv[self.owner])
        self._integrals: tuple[list[np.ndarray], np.ndarray] | None = None

    def __call__(self, x: np.ndarray, owner: np.ndarray, order: int = 2) -> np.ndarray:
        """z and its θ-derivatives at angles ``x`` of the pieces ``owner``."""
        return self.sys(x, self.pv[owner], order)

    def largest(self, g: np.ndarray) -> np.ndarray:
        """Each piece's largest finite |g| over its grid (g: a row per grid angle)."""
        a = np.abs(np.where(np.isfinite(g), g, 0.0))
        return np.maximum.reduceat(a.reshape(a.shape[0], -1).max(axis=1), self.starts)

    def roots(
        self, fs: list[Quantity], k: int, falling: int = 0, polisher: Polisher | None = None
    ) -> list[Found]:
        """Each quantity's roots of its row k (0: value, 1: derivative) in the pieces, and the
        piece of each: sign changes on the grid, polished together (``roots.polish`` on rows
        k and k + 1: ``polisher``'s compiled steps on them where the one quantity has one,
        else ``roots.rtsafe``); only the falling ones for the first ``falling`` quantities
        (their derivative's: maxima)."""
        c = self.cells
        which, at, f_lo, f_hi, scale = [], [], [], [], []
        for i, f in enumerate(fs):
            g = f(self.z)[k]
            down = (g[c] > 0) & (g[c + 1] < 0)
            cc = c[down if i < falling else down | (g[c] < 0) & (g[c + 1] > 0)]
            which.append(np.full(cc.size, i))
            at.append(cc)
            f_lo.append(g[cc])
            f_hi.append(g[cc + 1])
            scale.append(self.largest(g)[self.owner[cc]])
        w, cc = np.concatenate(which), np.concatenate(at)
        owner = self.owner[cc]

        def fd(x: np.ndarray, j: np.ndarray) -> np.ndarray:  # roots j's rows at x
            z = self(x, owner[j])
            out = np.empty((2, x.size))
            for i, f in enumerate(fs):
                mine = w[j] == i
                if mine.any():
                    out[:, mine] = f(z[:, mine])[k : k + 2]
            return out

        lo, hi = self.grid[cc], self.grid[cc + 1]
        a, b, size = (np.concatenate(v) for v in (f_lo, f_hi, scale))
        if polisher is None:
            every = np.arange(cc.size)
            x = rtsafe(lambda y: fd(y, every), lo, hi, a, b, size)
        else:  # the one quantity's rows k and k + 1 are the polisher's one row and its derivative
            one = np.zeros(cc.size, dtype=int)
            x = polish(polisher, fd, one, lo, hi, a, b, size, self.pv[owner])
        return [(x[w == i], owner[w == i]) for i in range(len(fs))]

    def integrals(self) -> tuple[list[np.ndarray], np.ndarray]:
        """Each piece's panels' edges, and ∫ T dθ and ∫ T² dθ over every panel (shape
        (2, panels), the pieces' in turn, each's in order): the adaptive quadrature above,
        each round's panels in one evaluation; once."""
        if self._integrals is None:
            scale = self.largest(self.z[0, :, 0]).max()  # the turn's: its rounding's size
            spans = zip(self.lo, self.hi, strict=True)
            first = [np.linspace(a, b, math.ceil((b - a) / PANEL) + 1) for a, b in spans]
            owner = np.repeat(np.arange(len(first)), [e.size - 1 for e in first])
            lo = np.concatenate([e[:-1] for e in first])
            hi = np.concatenate([e[1:] for e in first])
            kept: list[tuple[np.ndarray, ...]] = []  # owner, lo and sums of accepted panels
            for halving in range(HALVINGS + 1):
                sums, check = self.gauss(lo, hi, owner, 2, (RULE, CHECK))
                size = np.array([[scale], [scale**2]]) * (hi - lo)
                ok = np.all(np.abs(sums - check) <= AGREE * size, axis=0)
                if halving == HALVINGS:
                    ok[:] = True
                kept.append((owner[ok], lo[ok], sums[:, ok]))
                mid = 0.5 * (lo + hi)[~ok]
                owner = np.repeat(owner[~ok], 2)
                lo, hi = np.ravel([lo[~ok], mid], "F"), np.ravel([mid, hi[~ok]], "F")
                if not owner.size:
                    break
            owner, lo, sums = (np.concatenate(c, axis=-1) for c in zip(*kept, strict=True))
            order = np.lexsort((lo, owner))
            owner, lo = owner[order], lo[order]
            edges = [
                np.append(lo[owner == i], b) if a < b else np.array([a])
                for i, (a, b) in enumerate(zip(self.lo, self.hi, strict=True))
            ]
            self._integrals = edges, sums[:, order]
        return self._integrals

    def gauss(
        self,
        lo: np.ndarray,
        hi: np.ndarray,
        owner: np.ndarray,
        powers: int,
        rules: tuple[tuple[np.ndarray, np.ndarray], ...] = (RULE,),
    ) -> np.ndarray:
        """∫ T^k dθ over each [lo, hi] of the pieces ``owner``, for k = 1 … powers, by each of
        ``rules`` (Gauss–Legendre nodes and weights), in one evaluation: shape (rules, powers,
        spans)."""
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        x = np.concatenate([(mid[:, None] + half[:, None] * n[None, :]).ravel() for n, _ in rules])
        own = np.concatenate([np.repeat(owner, n.size) for n, _ in rules])
        cuts = np.cumsum([lo.size * n.size for n, _ in rules])[:-1]
        t = np.split(self(x, own, 0)[0, :, 0], cuts)
        return np.array(
            [
                [(v.reshape(lo.size, w.size) ** k @ w) * half for k in range(1, powers + 1)]
                for v, (_, w) in zip(t, rules, strict=True)
            ]
        )
