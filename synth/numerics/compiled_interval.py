"""``interval``'s enclosures compiled to C: the same steps on (lo, hi) doubles in one loop
over the boxes, nanoseconds per instruction where numpy pays a call per instruction.

``CompiledInterval(fn)`` and ``CompiledCentred(fn, wrt, continuous)`` take and give what
``Interval`` and ``Centred`` do (they are subclasses); where no library can be built or loaded
(``SYNTH_NATIVE=0``, no C compiler, an unwritable cache) their numpy call runs.

The C comes from the numpy evaluator's own walk (``graph``, ``Interval``'s live steps): each
step calls a C helper below that restates its numpy rule operation for operation, with the
same margins (``REL``, ``TINY``, ``SLACK``, ``PI_UP``) and ``np.nextafter``, ``np.minimum``
(NaN wins), ``np.fmin`` (NaN loses) bit for bit. + − × ÷ √ round correctly in C as in numpy:
the same bits; exp, log, tan, … are glibc's, not numpy's (an ulp apart here and there, which
``REL``'s 64 ulp cover alike). The flags are bits (1 partial, 2 branched, 4 jumps) OR-ed from
a step's arguments into its result: an output's are its flagged ancestors', as ``Interval``
gathers them. Built with ``native.FLAGS``: no fast-math, no fused multiply-adds.
"""

from __future__ import annotations

import ctypes
import hashlib
import itertools
import math
import os
from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing as npt

from . import interval, native
from .interval import Centred, Enclosure, Interval, bounds, graph

BITS = {
    interval.PARTIAL: 1,
    interval.BRANCHED: 2,
    interval.JUMP: 4,
}  # a mask kind's bit in the flags byte


def literal(v: float) -> str:
    """A double as an exact C literal."""
    if math.isnan(v):
        return "NAN"
    if math.isinf(v):
        return "INFINITY" if v > 0 else "(-INFINITY)"
    return f"({float(v).hex()})"


# the margins, and the phases of sin's and cos's troughs and peaks and of tan's poles
CONSTANTS = {
    **{k: getattr(interval, k) for k in ("REL", "TINY", "SLACK", "PI_UP", "HALF_PI", "TAU")},
    **{"PI": math.pi, "POLE": math.pi / 2, "SIN_LOW": math.pi / 2 + math.pi},
    **{"SIN_HIGH": math.pi / 2, "COS_LOW": 0.0 + math.pi, "COS_HIGH": 0.0},
}
PRELUDE = (
    """#include <math.h>
#include <stdint.h>
#include <string.h>
typedef struct { double l, h; } P;
#define S static inline
#define MAXD 0x1.fffffffffffffp+1023
"""
    + "".join(f"#define {k} {literal(v)}\n" for k, v in CONSTANTS.items())
    + r"""
S P pair(double a, double b) { P r = {a, b}; return r; }
/* np.nextafter(x, ±inf), bit for bit (NaN, ±inf, ±0, subnormals) */
S double up(double x) {
  uint64_t u;
  double y;
  memcpy(&u, &x, 8);
  u = x > 0 ? u + 1 : u - 1;
  memcpy(&y, &u, 8);
  y = x == 0 ? 0x1p-1074 : y;
  return x < INFINITY ? y : x;
}
S double dn(double x) { return -up(-x); }
/* np.minimum, np.maximum (NaN wins), np.fmin, np.fmax (NaN loses), np.clip */
S double mnN(double a, double b) { return a < b ? a : (a != a ? a : b); }
S double mxN(double a, double b) { return a > b ? a : (a != a ? a : b); }
S double fmn(double a, double b) { return a < b ? a : (b != b ? a : b); }
S double fmx(double a, double b) { return a > b ? a : (b != b ? a : b); }
S double cl(double v, double a, double b) { return mnN(mxN(v, a), b); }
S P clp(P r, double a, double b) { return pair(cl(r.l, a, b), cl(r.h, a, b)); }
S P out(P y) { return pair(dn(y.l), up(y.h)); }
S P sane(P r) { return pair(r.l == r.l ? r.l : -INFINITY, r.h == r.h ? r.h : INFINITY); }
S P ext(double a, double b, double c, double d) {
  return pair(fmn(fmn(fmn(a, b), c), d), fmx(fmx(fmx(a, b), c), d));
}
S P widen(P y) {
  double a = mnN(fabs(y.l), MAXD) * REL + TINY, b = mnN(fabs(y.h), MAXD) * REL + TINY;
  return pair(mnN(y.l + a * -1.0, MAXD), mxN(y.h + b, -MAXD));
}
S int crosses(P x, double phase, double period) {
  double u0 = (x.l - phase) / period, u1 = (x.h - phase) / period;
  double slack = SLACK * (1.0 + fabs(u0) + fabs(u1));
  return !(floor(u1 + slack) < u0 - slack);
}
S P add(P x, P y) { return out(pair(x.l + y.l, x.h + y.h)); }
S P sub(P x, P y) { return out(pair(x.l - y.h, x.h - y.l)); }
/* the corners' extremes rounded out, NaN aside (then unbounded); without a NaN, as fast as
   min and max go (the same bits after rounding: only a zero's sign may differ) */
S double lt(double a, double b) { return a < b ? a : b; }
S double gt(double a, double b) { return a > b ? a : b; }
S P hull(double a, double b, double c, double d) {
  if (a == a && b == b && c == c && d == d)
    return out(pair(lt(lt(a, b), lt(c, d)), gt(gt(a, b), gt(c, d))));
  return sane(out(ext(a, b, c, d)));
}
S P mul(P x, P y) { return hull(x.l * y.l, x.l * y.h, x.h * y.l, x.h * y.h); }
S P dv(P x, P y, unsigned *m) {
  *m = y.l <= 0 && y.h >= 0;
  return *m ? pair(-INFINITY, INFINITY) : hull(x.l / y.l, x.l / y.h, x.h / y.l, x.h / y.h);
}
S P inv(P x, unsigned *m) { return dv(pair(1.0, 1.0), x, m); }
S P neg(P x) { return pair(-x.h, -x.l); }
S P twice(P x) { return out(pair(2.0 * x.l, 2.0 * x.h)); }
S P ab(P x) { return pair(mxN(mxN(x.l, -x.h), 0.0), -mnN(x.l, -x.h)); }
S P sq(P x) { P a = ab(x); return clp(out(pair(a.l * a.l, a.h * a.h)), 0.0, INFINITY); }
S P mn2(P x, P y) { return pair(mnN(x.l, y.l), mnN(x.h, y.h)); }
S P mx2(P x, P y) { return pair(mxN(x.l, y.l), mxN(x.h, y.h)); }
S P hyp(P x, P y) {
  P a = ab(x), b = ab(y);
  return clp(widen(pair(hypot(a.l, b.l), hypot(a.h, b.h))), 0.0, INFINITY);
}
/* a monotone function: clipped to [a, b] (if dom; mask: it left it), the ends' images
   (swapped if falling) rounded out (e) or widened, within [s, t] */
#define MONO(name, f, e, dom, a, b, s, t, falling) \
  S P name(P x, unsigned *m) { \
    P z = dom ? clp(x, a, b) : x; \
    P y = falling ? pair(f(z.h), f(z.l)) : pair(f(z.l), f(z.h)); \
    *m = dom && (x.l < a || x.h > b); \
    return clp(e ? out(y) : widen(y), s, t); \
  }
MONO(sqrt_, sqrt, 1, 1, 0.0, INFINITY, 0.0, INFINITY, 0)
MONO(exp_, exp, 0, 0, -INFINITY, INFINITY, 0.0, INFINITY, 0)
MONO(log_, log, 0, 1, 0.0, INFINITY, -INFINITY, INFINITY, 0)
MONO(asin_, asin, 0, 1, -1.0, 1.0, -HALF_PI, HALF_PI, 0)
MONO(acos_, acos, 0, 1, -1.0, 1.0, 0.0, PI_UP, 1)
MONO(atan_, atan, 0, 0, -INFINITY, INFINITY, -HALF_PI, HALF_PI, 0)
/* sin, cos: the ends' images, -1 and 1 where the interval may hold a trough or a peak */
#define PERIODIC(name, f, low, high) \
  S P name(P x) { \
    double a = f(x.l), b = x.h == x.l ? a : f(x.h); \
    P r = widen(pair(mnN(a, b), mxN(a, b))); \
    return clp(pair(crosses(x, low, TAU) ? -1.0 : r.l, crosses(x, high, TAU) ? 1.0 : r.h), \
               -1.0, 1.0); \
  }
PERIODIC(sin_, sin, SIN_LOW, SIN_HIGH)
PERIODIC(cos_, cos, COS_LOW, COS_HIGH)
S P tan_(P x) {
  return crosses(x, POLE, PI) ? pair(-INFINITY, INFINITY) : widen(pair(tan(x.l), tan(x.h)));
}
S P atan2_(P y, P x, unsigned *m) {
  *m = x.l <= 0 && y.l <= 0 && y.h >= 0;
  return clp(*m ? pair(-INFINITY, INFINITY)
                : widen(ext(atan2(y.l, x.l), atan2(y.l, x.h), atan2(y.h, x.l), atan2(y.h, x.h))),
             -PI_UP, PI_UP);
}
S P gpow(P x, P y, unsigned *m) { unsigned d; return exp_(mul(y, log_(x, m)), &d); }
S P rpow(P x, double c, unsigned *m) { /* x**c, c real: x >= 0 */
  P z = clp(x, 0.0, INFINITY);
  *m = x.l < 0.0 || x.h > INFINITY;
  return widen(c < 0 ? pair(pow(z.h, c), pow(z.l, c)) : pair(pow(z.l, c), pow(z.h, c)));
}
S P ipow(P x, double n, int even) { /* x**n, n a positive integer: of |x| if even */
  P z = even ? ab(x) : x, r = widen(pair(pow(z.l, n), pow(z.h, n)));
  return even ? clp(r, 0.0, INFINITY) : r;
}
S int nz(P x) { return x.l > 0 || x.h < 0; }
S int zr(P x) { return x.l == 0 && x.h == 0; }
S int same(P x, P y) { return x.l == x.h && y.l == y.h && x.l == y.l; }
S int apart(P x, P y) { return x.h < y.l || y.h < x.l; }
S P truth(int yes, int no, unsigned *m) {
  *m = !(yes || no);
  return pair(yes ? 1.0 : 0.0, no ? 0.0 : 1.0);
}
S double sg(double v) { return v > 0 ? 1.0 : (v < 0 ? -1.0 : v); }
S P sign_(P x, unsigned *m) {
  *m = x.l <= 0 && x.h >= 0 && x.l < x.h;
  return pair(sg(x.l), sg(x.h));
}
S P sel(P c, P a, P b, unsigned *m) {
  int yes = nz(c), no = zr(c);
  *m = !(yes || no);
  return yes ? a : (no ? b : pair(mnN(a.l, b.l), mxN(a.h, b.h)));
}
"""
)
# each operation's C, of its arguments {0}, {1}, … and its mask's address {m}
CALLS = {
    ca.OP_ADD: "add({0}, {1})",
    ca.OP_SUB: "sub({0}, {1})",
    ca.OP_MUL: "mul({0}, {1})",
    ca.OP_DIV: "dv({0}, {1}, {m})",
    ca.OP_INV: "inv({0}, {m})",
    ca.OP_NEG: "neg({0})",
    ca.OP_TWICE: "twice({0})",
    ca.OP_SQ: "sq({0})",
    ca.OP_FABS: "ab({0})",
    ca.OP_FMIN: "mn2({0}, {1})",
    ca.OP_FMAX: "mx2({0}, {1})",
    ca.OP_HYPOT: "hyp({0}, {1})",
    ca.OP_SQRT: "sqrt_({0}, {m})",
    ca.OP_EXP: "exp_({0}, {m})",
    ca.OP_LOG: "log_({0}, {m})",
    ca.OP_SIN: "sin_({0})",
    ca.OP_COS: "cos_({0})",
    ca.OP_TAN: "tan_({0})",
    ca.OP_ASIN: "asin_({0}, {m})",
    ca.OP_ACOS: "acos_({0}, {m})",
    ca.OP_ATAN: "atan_({0}, {m})",
    ca.OP_ATAN2: "atan2_({0}, {1}, {m})",
    ca.OP_POW: "gpow({0}, {1}, {m})",
    ca.OP_LT: "truth({0}.h < {1}.l, {0}.l >= {1}.h, {m})",
    ca.OP_LE: "truth({0}.h <= {1}.l, {0}.l > {1}.h, {m})",
    ca.OP_EQ: "truth(same({0}, {1}), apart({0}, {1}), {m})",
    ca.OP_NE: "truth(apart({0}, {1}), same({0}, {1}), {m})",
    ca.OP_NOT: "truth(zr({0}), nz({0}), {m})",
    ca.OP_AND: "truth(nz({0}) && nz({1}), zr({0}) || zr({1}), {m})",
    ca.OP_OR: "truth(nz({0}) || nz({1}), zr({0}) && zr({1}), {m})",
    ca.OP_SIGN: "sign_({0}, {m})",
    ca.OP_IF_ELSE_ZERO: "sel({0}, {1}, pair(0.0, 0.0), {m})",
}
SELECT = "sel({0}, {1}, {2}, {m})"  # the if_else rewrite: c ? a : b


def call(nodes: list[Any], op: int, args: tuple[int, ...]) -> str:
    """One step's C (``graph``'s rewrites: x·x has one argument, if_else three, a constant
    power its exponent's node)."""
    if op == ca.OP_MUL and len(args) == 1:
        return CALLS[ca.OP_SQ]
    if op == ca.OP_ADD and len(args) == 3:
        return SELECT
    if op in (ca.OP_POW, ca.OP_CONSTPOW):
        if nodes[args[1]][0] != ca.OP_CONST:
            return CALLS[ca.OP_POW]
        c = float(nodes[args[1]][2])
        if not math.isfinite(c) or c != int(c):
            return f"rpow({{0}}, {literal(c)}, {{m}})"
        n = int(c)
        grow = f"ipow({{0}}, {literal(abs(n))}, {int(n % 2 == 0)})"
        if n >= 0:
            return grow if n else "pair(1.0, 1.0)"
        return f"dv(pair(1.0, 1.0), {grow}, {{m}})"
    return CALLS[op]


def box(ev: Interval, name: str) -> str:
    """A C function enclosing ``ev``'s function over one box: (lo, hi) of every input nonzero
    in order, (lo, hi, flags) of every output nonzero."""
    nodes = graph(ev.fn)[0]
    offsets = np.cumsum([0, *ev.nnz_in]).tolist()
    lines = [
        f"static void {name}(const double *L, const double *H, double *ol, double *oh, "
        "unsigned char *of) {"
    ]
    for k, (i, nz) in ev.inputs:
        lines.append(f"  P v{k} = pair(L[{offsets[i] + nz}], H[{offsets[i] + nz}]);")
    for k, c in ev.constants:
        lines.append(f"  P v{k} = pair({literal(c[0, 0])}, {literal(c[1, 0])});")
    flagged: set[int] = set()  # the nodes with a flagged ancestor (themselves too)
    for k, _, kind, args, _ in ev.steps:
        template = call(nodes, nodes[k][0], args)
        mask = f"&m{k}" if "{m}" in template else ""
        if mask:
            lines.append(f"  unsigned m{k};")
        text = template.format(*(f"v{a}" for a in args), m=mask)
        lines.append(f"  P v{k} = {text};")
        bits = [f"f{a}" for a in dict.fromkeys(args) if a in flagged]
        if kind:
            bits.append(f"(m{k} * {BITS[kind]}u)")
        if bits:
            flagged.add(k)
            lines.append(f"  unsigned f{k} = {' | '.join(bits)};")
    written = set()
    out = np.cumsum([0, *ev.nnz_out]).tolist()
    for i, nz, k, _ in ev.outputs:
        j = out[i] + nz
        written.add(j)
        flag = f"f{k}" if k in flagged else "0"
        lines.append(f"  ol[{j}] = v{k}.l; oh[{j}] = v{k}.h; of[{j}] = (unsigned char){flag};")
    for j in sorted(set(range(out[-1])) - written):
        lines.append(f"  ol[{j}] = 0.0; oh[{j}] = 0.0; of[{j}] = 0;")
    return "\n".join([*lines, "}\n"])


def gather(nnz: Sequence[int]) -> str:
    """C that copies box b's bounds of every input nonzero into L, H."""
    lines, at = [f"    double L[{max(1, sum(nnz))}], H[{max(1, sum(nnz))}];"], 0
    for i, m in enumerate(nnz):
        lines.append(
            f"    for (long j = 0; j < {m}; j++) {{ L[{at} + j] = lo[{i}][b * step[{i}] + j]; "
            f"H[{at} + j] = hi[{i}][b * step[{i}] + j]; }}"
        )
        at += m
    return "\n".join(lines)


ENTRY = "void {name}(long n, const double *const *lo, const double *const *hi, const long *step,"
ENTRY += " double *ol, double *oh, unsigned char *of) {{\n  for (long b = 0; b < n; b++) {{\n"


def naive_source(ev: Interval) -> str:
    """The library of ``CompiledInterval``: ``naive`` over n boxes."""
    m = sum(ev.nnz_out)
    return (
        PRELUDE
        + box(ev, "f")
        + ENTRY.format(name="naive")
        + gather(ev.nnz_in)
        + f"\n    f(L, H, ol + b * {m}, oh + b * {m}, of + b * {m});\n  }}\n}}\n"
    )


def centred_source(c: Centred) -> str:
    """The library of ``CompiledCentred``: ``centred`` over n boxes, ``Centred``'s call in C:
    the joint enclosure of f and its Jacobian J over the box, f at the centre c of the ``wrt``
    inputs (the others over their boxes), P − c rounded out (0 where it is 0), each term
    J·(P − c) rounded out (0·∞ as 0) and added in order, rounded out; the form intersected with
    the joint's f unless a flag or a non-finite form forbids it."""
    m, k, nnz = c.m, c.k, c.naive.nnz_in
    offsets = np.cumsum([0, *nnz]).tolist()
    wrt = [offsets[i] + j for i in c.wrt for j in range(nnz[i])]
    forbid = 1 | 4 | (0 if c.continuous else 2)
    size = max(1, m * (k + 1))
    body = [
        f"    double jl[{size}], jh[{size}]; unsigned char jf[{size}];",
        "    double *lo_ = ol + b * NOUT, *hi_ = oh + b * NOUT;",
        "    unsigned char *fl_ = of + b * NOUT;",
        "    joint(L, H, jl, jh, jf);",
        "    for (int r = 0; r < NOUT; r++) { lo_[r] = jl[r]; hi_[r] = jh[r]; fl_[r] = jf[r]; }",
    ]
    if k:
        body += [
            f"    double dl[{k}], dh[{k}], al[{m or 1}], ah[{m or 1}]; unsigned char af[{m or 1}];",
            f"    static const int W[NWRT] = {{{', '.join(map(str, wrt))}}};",
            "    for (int c = 0; c < NWRT; c++) {",
            "      int i = W[c];",
            "      double mid = cl(0.5 * L[i] + 0.5 * H[i], L[i], H[i]);",
            "      double a = L[i] - mid, e = H[i] - mid;",
            "      dl[c] = a == 0 ? 0.0 : dn(a); dh[c] = e == 0 ? 0.0 : up(e);",
            "      L[i] = H[i] = mid;",
            "    }",
            "    f(L, H, al, ah, af);",
            "    for (int r = 0; r < NOUT; r++) {",
            f"      double fl = al[r], fh = ah[r]; int bad = (jf[r] & {forbid}) != 0;",
            "      for (int c = 0; c < NWRT; c++) {",
            "        int j = NOUT + c * NOUT + r;",
            "        double p = jl[j] * dl[c], q = jl[j] * dh[c], s = jh[j] * dl[c];",
            "        double t = jh[j] * dh[c];",
            "        p = p == p ? p : 0.0; q = q == q ? q : 0.0;",
            "        s = s == s ? s : 0.0; t = t == t ? t : 0.0;",
            "        bad |= jf[j] & 1;",
            "        fl = dn(fl + dn(mnN(mnN(mnN(p, q), s), t)));",
            "        fh = up(fh + up(mxN(mxN(mxN(p, q), s), t)));",
            "      }",
            "      bad |= !(isfinite(fl) && isfinite(fh));",
            "      if (!bad) { lo_[r] = mxN(jl[r], fl); hi_[r] = mnN(jh[r], fh); }",
            "    }",
        ]
    return (
        PRELUDE
        + f"#define NOUT {m}\n#define NWRT {k}\n"
        + box(c.naive, "f")
        + box(c.joint, "joint")
        + ENTRY.format(name="centred")
        + gather(nnz)
        + "\n"
        + "\n".join(body)
        + "\n  }\n}\n"
    )


def load(source: str, name: str, entry: str) -> Any:
    """The function ``entry`` of the library built from ``source`` (from the cache, built
    there first if need be), or None where none can be built or loaded."""
    if os.environ.get("SYNTH_NATIVE", "1") == "0":
        return None
    key = hashlib.sha256("\0".join((*native.FLAGS, source)).encode()).hexdigest()
    path = native.cache() / f"interval_{name}_{key[:20]}.so"
    if not path.exists() and not native.build_library(source, path):
        return None
    try:
        fn = getattr(ctypes.CDLL(str(path)), entry)
    except (OSError, AttributeError):  # another machine's, or truncated
        return None
    fn.argtypes, fn.restype = [ctypes.c_long, *[ctypes.c_void_p] * 6], None
    return fn


def address(a: np.ndarray) -> int:
    """Where an array's data starts (quicker than ``a.ctypes.data``)."""
    return int(a.__array_interface__["data"][0])


def run(
    entry: Any, lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike], ev: Interval
) -> Enclosure:
    """A library's entry over the boxes of ``ev``'s inputs, the bounds checked as numpy's (a
    shared input's one row is read by every box)."""
    boxes, n = bounds(lo, hi, ev.nnz_in)
    keep = [np.ascontiguousarray(a) for ab in boxes for a in ab]  # alive through the call
    count = max(1, len(boxes))
    ends = [(ctypes.c_void_p * count)(*map(address, keep[e::2])) for e in (0, 1)]
    step = (ctypes.c_long * count)(*(0 if len(a) == 1 else a.shape[1] for a in keep[::2]))
    m = sum(ev.nnz_out)
    olo, ohi, flags = np.empty((n, m)), np.empty((n, m)), np.empty((n, m), np.uint8)
    entry(n, *ends, step, address(olo), address(ohi), address(flags))
    cuts = list(itertools.accumulate(ev.nnz_out))[:-1]
    bits = (flags & 1 > 0, flags & 2 > 0, flags & 4 > 0)
    if not cuts:  # one output
        return Enclosure([olo], [ohi], [bits[0]], [bits[1]], [bits[2]])
    a, b, c, d, e = (np.split(x, cuts, axis=1) for x in (olo, ohi, *bits))
    return Enclosure(a, b, c, d, e)


class CompiledInterval(Interval):
    """``Interval``, compiled (its numpy call where no library can be had)."""

    def __init__(self, fn: ca.Function) -> None:
        super().__init__(fn)
        self.library = load(naive_source(self), self.fn.name(), "naive")

    def __call__(self, lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike]) -> Enclosure:
        """The enclosure over each box (as ``Interval``'s call)."""
        if self.library is None:
            return super().__call__(lo, hi)
        return run(self.library, lo, hi, self)


class CompiledCentred(Centred):
    """``Centred``, compiled (its numpy call where no library can be had)."""

    def __init__(
        self, fn: ca.Function, wrt: Sequence[int] | None = None, continuous: bool = False
    ) -> None:
        super().__init__(fn, wrt, continuous)
        self.library = load(centred_source(self), self.naive.fn.name(), "centred")

    def __call__(self, lo: Sequence[npt.ArrayLike], hi: Sequence[npt.ArrayLike]) -> Enclosure:
        """The intersected enclosure over each box (as ``Centred``'s call)."""
        if self.library is None:
            return super().__call__(lo, hi)
        return run(self.library, lo, hi, self.naive)
