/* The tunnel the projectile opens (docs/theory.md §8.7), its one home: target_kernel.c includes this file, so
 * the single rigid path, the batched rigid shots and the deformable load all record it and locate their points
 * in it with this text.
 *
 * The tunnel is a chain of stations along the path of the projectile's widest section (the "shoulder": the
 * section where the nose first reaches the full calibre): each station a centre c, a unit direction t along the
 * path, its arc length s and, in S angular sectors about t, the radius a the cavity has been opened to there
 * (the shoulder's radius a0 when recorded, pushed outward where the body later expands the wall). A station is
 * recorded once the shoulder is below the face and has advanced `spacing` along the path since the last one;
 * the shoulder itself, where it is now, is the tunnel's open end.
 *
 * A surface point at body-axial distance xi behind the tip (xi_sh: the shoulder's) lies, when the body follows its
 * tunnel, at arc length s_now - (xi - xi_sh); one projection onto the interpolated axis corrects that for a body
 * turned in its tunnel. Its distance rho from the axis against the wall's radius a there gives delta = rho - a
 * (> 0: pushed into the wall) and the outward unit vector er. Points ahead of the shoulder are not in the tunnel
 * (the nose, which opens it, follows the law of the open face).
 *
 * The state is one flat array of doubles (fepen.laws.tunnel.Tunnel owns it in Python; rigid_batch.c one per
 * shot): a header of T_HEADER numbers, then the stations, each T_STATION + S numbers. */
#ifndef FEPEN_TUNNEL_KERNEL
#define FEPEN_TUNNEL_KERNEL
#include <math.h>
#include <stdint.h>

#include "tunnel_kernel.h"

static inline double *tunnel_station(double *T, int32_t k) {
    return T + T_HEADER + (int64_t)k * (T_STATION + (int32_t)T[T_S]);
}

static inline double tdot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Where a station-to-be lies: the centre, direction and arc length of the interpolated axis at arc length s, the
 * two stations around it (ib == m: the shoulder now, the open end) and the weight of the second. */
typedef struct {
    double c[3], t[3], w;
    int32_t ia, ib;
} TunnelAt;

/* the shoulder now as a station: its centre, its direction from the last station, its arc length */
static void tunnel_open_end(const double *T, double *c, double *t, double *s) {
    const int32_t m = (int32_t)T[T_M];
    const double *last = tunnel_station((double *)T, m - 1);
    double d[3] = {T[T_CS] - last[T_C], T[T_CS + 1] - last[T_C + 1], T[T_CS + 2] - last[T_C + 2]};
    double along = tdot(d, last + T_T), len = sqrt(tdot(d, d));
    for (int j = 0; j < 3; ++j) {
        c[j] = T[T_CS + j];
        t[j] = len > 1e-12 ? d[j] / len : last[T_T + j];
    }
    *s = last[T_ARC] + along;
}

static void tunnel_at(const double *T, double s, const double *c_end, const double *t_end, double s_end,
                      int32_t hint, TunnelAt *at) {
    const int32_t m = (int32_t)T[T_M];
    int32_t lo = 0, hi = m; /* stations 0..m-1 recorded, m the open end */
    if (s >= tunnel_station((double *)T, m - 1)[T_ARC]) {
        lo = m - 1;
    } else {
        /* the last recorded station at or before s (the arcs increase: one answer however it is searched); a
         * hint (a nearby station, or -1) narrows the bracket by doubling steps from it first */
        if (hint >= 0 && hint < m) {
            if (tunnel_station((double *)T, hint)[T_ARC] <= s) { /* arc[lo] <= s; then arc[hi] > s or hi = m */
                int32_t step = 1;
                lo = hint;
                while (lo + step < m && tunnel_station((double *)T, lo + step)[T_ARC] <= s) {
                    lo += step;
                    step *= 2;
                }
                hi = lo + step < m ? lo + step : m;
            } else { /* arc[hint] > s: back from it by doubling steps; then arc[lo] <= s or lo = 0 */
                int32_t step = 1;
                hi = hint;
                while (hi - step >= 0 && tunnel_station((double *)T, hi - step)[T_ARC] > s) {
                    hi -= step;
                    step *= 2;
                }
                lo = hi - step > 0 ? hi - step : 0;
            }
        }
        while (hi - lo > 1) {
            int32_t mid = (lo + hi) / 2;
            if (tunnel_station((double *)T, mid)[T_ARC] <= s) lo = mid;
            else hi = mid;
        }
    }
    const double *a = tunnel_station((double *)T, lo);
    const double *b_c = lo + 1 < m ? tunnel_station((double *)T, lo + 1) + T_C : c_end;
    const double *b_t = lo + 1 < m ? tunnel_station((double *)T, lo + 1) + T_T : t_end;
    double sb = lo + 1 < m ? tunnel_station((double *)T, lo + 1)[T_ARC] : s_end;
    double span = sb - a[T_ARC], w = span > 1e-15 ? (s - a[T_ARC]) / span : 1.0;
    w = w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w);
    double n2 = 0.0;
    for (int j = 0; j < 3; ++j) {
        at->c[j] = a[T_C + j] + w * (b_c[j] - a[T_C + j]);
        at->t[j] = a[T_T + j] + w * (b_t[j] - a[T_T + j]);
        n2 += at->t[j] * at->t[j];
    }
    double nt = sqrt(n2);
    for (int j = 0; j < 3; ++j) at->t[j] /= nt;
    at->ia = lo;
    at->ib = lo + 1;
    at->w = w;
}

/* The open end of one call's tunnel (tunnel_open_end), computed once per call after the station is recorded:
 * every point of the call is located against the same end. hint: the station the call's last ring was found at
 * (-1: none yet). The points of a call come ring by ring (the points of a ring share their distance xi behind the
 * tip); a ring is located once (tunnel_ring): its centre on the body's axis projected onto the tunnel's axis, the
 * station there, the sector frame e1 of that station's direction. Its points are then measured against that
 * place alone: their offsets from the axis, their sectors, the wall's radius there. */
typedef struct {
    double c[3], t[3], s;
    int32_t hint;
    /* the last ring: its xi, where it lies, the sector frame there (e1, not of unit length, n1sq = e1 . e1) */
    double ring_xi;
    TunnelAt ring;
    double e1[3], n1sq;
    /* the square of the largest distance from the axis at which a point of the ring is clear of the wall
     * (tunnel_locate's clear_ok) */
    double clear2;
    /* the ring's arc length, and how far along the path from the ring's centre a point may lie and still be
     * measured where its ring lies (RING_REACH of the spacing; beyond, at its own place) */
    double ring_s, reach;
    int32_t has_ring;
} TunnelEnd;

static inline void tunnel_end(const double *T, TunnelEnd *e) {
    e->hint = -1;
    e->has_ring = 0;
    if ((int32_t)T[T_M] >= 1) tunnel_open_end(T, e->c, e->t, &e->s);
}

/* The sector of the angle theta = atan2(y, x) in [-pi, pi]: floor((theta + pi) / (2 pi) S), clamped to 0..S-1. The
 * angle is first taken from a polynomial (Abramowitz and Stegun 4.4.47, |error| <= 1e-5 rad); where that lies
 * within TUNNEL_SECTOR_MARGIN (ten times wider) of a sector's edge, the sector is taken from libm's atan2 as it
 * always was. Elsewhere both give the same sector: the same integer, without atan2, a square root and a division
 * on every point. */
#define TUNNEL_SECTOR_MARGIN 1e-4
static inline int32_t tunnel_sector_exact(double y, double x, int32_t S) {
    double theta = atan2(y, x);
    int32_t q = (int32_t)floor((theta + M_PI) / (2.0 * M_PI) * S);
    return q < 0 ? 0 : (q >= S ? S - 1 : q);
}

/* e1 of the sector's angle about the unit axis t: the world z axis's part across t (x when t is along z), not
 * yet of unit length; returns e1 . e1 */
static inline double tunnel_e1(const double *t, double *e1) {
    e1[0] = -t[2] * t[0]; e1[1] = -t[2] * t[1]; e1[2] = 1.0 - t[2] * t[2];
    double n1sq = tdot(e1, e1);
    if (n1sq < 1.0000001e-12 && sqrt(n1sq) < 1e-6) {
        e1[0] = 1.0 - t[0] * t[0]; e1[1] = -t[0] * t[1]; e1[2] = -t[0] * t[2];
        n1sq = tdot(e1, e1);
    }
    return n1sq;
}

/* r's sector about the unit axis t from e1 (not yet of unit length: e1 . e1 = n1sq). The polynomial takes r's
 * components along e1 and t x e1 as they are (a common positive scale leaves the angle as it is); the exact path
 * makes e1 a unit vector first, as it always did. */
static inline int32_t tunnel_sector(const double *r, const double *t, double *e1, double n1sq, int32_t S) {
    double e2[3] = {t[1] * e1[2] - t[2] * e1[1], t[2] * e1[0] - t[0] * e1[2], t[0] * e1[1] - t[1] * e1[0]};
    const double x = tdot(r, e1), y = tdot(r, e2);
    const double ax = fabs(x), ay = fabs(y), hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    if (hi > 0.0 && hi < INFINITY) {
        const double z = lo / hi, z2 = z * z;
        double a = z * (0.9998660 + z2 * (-0.3302995 + z2 * (0.1801410 + z2 * (-0.0851330 + z2 * 0.0208351))));
        if (ay > ax) a = 0.5 * M_PI - a;
        if (x < 0.0) a = M_PI - a;
        if (y < 0.0) a = -a;
        const double per_rad = S * (0.5 / M_PI), u = (a + M_PI) * per_rad, fl = floor(u);
        const double margin = TUNNEL_SECTOR_MARGIN * per_rad;
        if (u - fl > margin && fl + 1.0 - u > margin && fl >= 0.0 && fl < (double)S) return (int32_t)fl;
    }
    const double n1 = sqrt(n1sq);
    for (int j = 0; j < 3; ++j) e1[j] /= n1;
    double e2u[3] = {t[1] * e1[2] - t[2] * e1[1], t[2] * e1[0] - t[0] * e1[2], t[0] * e1[1] - t[1] * e1[0]};
    return tunnel_sector_exact(tdot(r, e2u), tdot(r, e1), S);
}

/* A point of a ring within this fraction of the station spacing of the ring's centre, along the path, is measured
 * where its ring lies (its station, sector frame and wall radii the ring's); one farther (a body turned across its
 * tunnel: a point A0 sin psi from the centre) where it lies itself, as every point was before issue 62 */
#define RING_REACH 0.05

/* Where the ring at body-axial distance xi lies in the tunnel (e: its open end): its centre on the body's axis
 * now (the shoulder's centre less xi - xi_sh along the body's axis), the station at that centre's arc length (its
 * distance behind the shoulder along the path, then one projection onto the axis there: a body turned in its
 * tunnel), the sector frame of that station's direction. Returns 0 when the ring is ahead of the shoulder (the
 * nose). */
static int tunnel_ring(const double *T, TunnelEnd *e, double xi) {
    const double c_end[3] = {e->c[0], e->c[1], e->c[2]}, s_end = e->s, back = xi - T[T_XI_SH];
    double s = s_end - back;
    if (s > s_end) return 0; /* ahead of the shoulder: the nose */
    const double s0 = tunnel_station((double *)T, 0)[T_ARC];
    if (s < s0) s = s0;
    TunnelAt at;
    tunnel_at(T, s, c_end, e->t, s_end, e->hint, &at);
    double d[3]; /* the ring's centre on the body's axis, against the station's centre */
    for (int j = 0; j < 3; ++j) d[j] = T[T_CS + j] - back * T[T_TS + j] - at.c[j];
    s += tdot(d, at.t);
    if (s > s_end) s = s_end;
    if (s < s0) s = s0;
    tunnel_at(T, s, c_end, e->t, s_end, at.ia, &e->ring);
    e->ring_s = s;
    e->reach = RING_REACH * T[T_SPACING];
    e->hint = e->ring.ia;
    e->n1sq = tunnel_e1(e->ring.t, e->e1);
    /* the wall's smallest radius about the ring (of its two stations' smallest radii: the interpolated radius of
     * every sector lies between its stations'), and a point's distance from the axis below which it cannot press
     * the wall: wall_push's round-off width added, then 1e-12 of it taken off, so that the few roundings of
     * tunnel_locate's delta never decide otherwise */
    const int32_t m = (int32_t)T[T_M];
    const double lo = tunnel_station((double *)T, e->ring.ia)[T_AMIN];
    const double hi = e->ring.ib < m ? tunnel_station((double *)T, e->ring.ib)[T_AMIN] : T[T_A0];
    const double amin = lo < hi ? lo : hi;
    const double clear = (amin + 1e-9 * T[T_A0]) * (1.0 - 1e-12);
    e->clear2 = clear > 0.0 ? clear * clear : 0.0;
    e->ring_xi = xi;
    e->has_ring = 1;
    return 1;
}

/* tunnel_locate's answers: not in the tunnel, clear of its wall (asked for), located */
enum { TUNNEL_OUT = 0, TUNNEL_IN = 1, TUNNEL_CLEAR = 2 };

/* tunnel_locate's measure of a point that is not clear (d: its offset from the ring's station, along: d's part
 * along the axis there): out of line, so that the clear test stays a few instructions in the law's loop */
__attribute__((noinline)) static int tunnel_place(const double *T, TunnelEnd *e, const double *p, double *d,
                                                  double along, double *delta, double *er, int32_t *kn,
                                                  int32_t *sec, double *rho) {
    const int32_t m = (int32_t)T[T_M], S = (int32_t)T[T_S];
    const TunnelAt *at = &e->ring;
    TunnelAt own;
    double r[3], e1[3], n1sq;
    if (fabs(along) > e->reach) { /* far along the path from its ring's centre: located at its own place */
        const double s0 = tunnel_station((double *)T, 0)[T_ARC];
        double s = e->ring_s + along;
        if (s > e->s) s = e->s;
        if (s < s0) s = s0;
        tunnel_at(T, s, e->c, e->t, e->s, at->ia, &own);
        at = &own;
        for (int j = 0; j < 3; ++j) d[j] = p[j] - at->c[j];
        along = tdot(d, at->t);
        n1sq = tunnel_e1(at->t, e1);
    } else {
        for (int j = 0; j < 3; ++j) e1[j] = e->e1[j];
        n1sq = e->n1sq;
    }
    for (int j = 0; j < 3; ++j) r[j] = d[j] - along * at->t[j];
    double rr = sqrt(tdot(r, r));
    if (!(rr > 1e-12)) return TUNNEL_OUT;
    for (int j = 0; j < 3; ++j) er[j] = r[j] / rr;
    const int32_t q = tunnel_sector(r, at->t, e1, n1sq, S); /* the sector: the angle of r about t from e1 */
    double a_lo = tunnel_station((double *)T, at->ia)[T_STATION + q];
    double a_hi = at->ib < m ? tunnel_station((double *)T, at->ib)[T_STATION + q] : T[T_A0];
    *delta = rr - (a_lo + at->w * (a_hi - a_lo));
    *rho = rr;
    *sec = q;
    *kn = at->w < 0.5 ? at->ia : (at->ib < m ? at->ib : -1);
    return TUNNEL_IN;
}

/* A point p at body-axial distance xi in the tunnel (e: its open end, tunnel_end): returns TUNNEL_IN with its
 * penetration of the wall delta (m), the outward unit vector er, its nearest recorded station kn (-1: the open
 * end) and sector sec and its distance rho from the axis; TUNNEL_OUT when it is not in the tunnel (ahead of the
 * shoulder, no station yet, or on the axis). The point is measured where its ring lies (tunnel_ring, once a ring).
 *
 * With clear_ok, TUNNEL_CLEAR (nothing else written) when the point is certainly clear of the wall: its squared
 * distance from the ring's axis below the wall's smallest radius about the ring and wall_push's round-off width
 * (clear2), before any square root or division. Most of a body that follows its own tunnel is clear of it, and the
 * law's loops skip those points so; the locate would find them unpressed, and the law would not load them. */
static inline int tunnel_locate(const double *T, TunnelEnd *e, const double *p, double xi, int clear_ok,
                                double *delta, double *er, int32_t *kn, int32_t *sec, double *rho) {
    if ((int32_t)T[T_M] < 1) return TUNNEL_OUT;
    if (!(e->has_ring && xi == e->ring_xi) && !tunnel_ring(T, e, xi)) return TUNNEL_OUT;
    const TunnelAt *at = &e->ring;
    double d[3] = {p[0] - at->c[0], p[1] - at->c[1], p[2] - at->c[2]};
    const double along = tdot(d, at->t);
    if (clear_ok && !(fabs(along) > e->reach)) {
        const double r[3] = {d[0] - along * at->t[0], d[1] - along * at->t[1], d[2] - along * at->t[2]};
        const double r2 = tdot(r, r);
        if (r2 < e->clear2 && r2 > 2e-24) return TUNNEL_CLEAR;
    }
    return tunnel_place(T, e, p, d, along, delta, er, kn, sec, rho);
}

/* A step's first stage: a new station at the shoulder once it is below the face and has advanced `spacing` along
 * the path since the last (none once the room is full: the tunnel then ends there). */
static void tunnel_record(double *T) {
    const int32_t m = (int32_t)T[T_M], S = (int32_t)T[T_S];
    if (!(T[T_CS + 1] < T[T_FACE]) || m >= (int32_t)T[T_CAP]) return;
    double *st = tunnel_station(T, m);
    if (m == 0) {
        for (int j = 0; j < 3; ++j) {
            st[T_C + j] = T[T_CS + j];
            st[T_T + j] = T[T_TS + j];
        }
        st[T_ARC] = 0.0;
    } else {
        double c[3], t[3], s;
        tunnel_open_end(T, c, t, &s);
        if (!(s - tunnel_station(T, m - 1)[T_ARC] >= T[T_SPACING])) return;
        for (int j = 0; j < 3; ++j) {
            st[T_C + j] = c[j];
            st[T_T + j] = t[j];
        }
        st[T_ARC] = s;
    }
    st[T_AMIN] = T[T_A0];
    for (int32_t q = 0; q < S; ++q) st[T_STATION + q] = T[T_A0];
    T[T_M] = m + 1;
}

/* The plastic cavity at station kn and sector sec opened out to radius r (it keeps the largest it was opened to):
 * the wall's yield (target_kernel.c's wall_yield) */
static void tunnel_widen(double *T, int32_t kn, int32_t sec, double r) {
    double *st = tunnel_station(T, kn), *a = st + T_STATION + sec;
    if (!(r > *a)) return;
    const double was = *a;
    *a = r;
    if (was > st[T_AMIN]) return; /* not the smallest: the smallest stays */
    double amin = INFINITY; /* the smallest grew, or was this one's: found again */
    for (int32_t q = 0; q < (int32_t)T[T_S]; ++q)
        if (st[T_STATION + q] < amin) amin = st[T_STATION + q];
    st[T_AMIN] = amin;
}
#endif
