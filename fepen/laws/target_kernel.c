/* The target law (docs/theory.md §8) on surface points, its one home: immersion, tunnel stress, wake,
 * separation, free surface, energy crater, sliding friction, and the tunnel's elastic-plastic wall
 * (tunnel_kernel.c), at
 * one point (law_at_point), and on k
 * points (point_forces, which fepen.laws.target.load_on_points calls through fepen.native before its
 * linear-crater scaling). tests/unit/laws/test_target_kernel.py checks it against an independent numpy
 * oracle of the equations and against their limits. Built once per machine, called by ctypes. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "target_kernel.h"

#define SIN_TOL 1e-9

#include "tunnel_kernel.c"

/* A point in the tunnel (tunnel_kernel.c): its push into the wall (m), the outward unit vector, the cavity's
 * radius a0 (m), and the wall's stiffness there (wall_stiffness: the same for every point of a call) */
typedef struct {
    double delta, er[3], a, k;
} WallHit;

static double clip01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

/* fmax(x, c) and fmin(x, c) for a bound c that is never NaN, the same value for every x (NaN included: then c)
 * and inlined (libm's are calls: a few per cent of a rigid shot) */
static inline double max_c(double x, double c) { return x > c ? x : c; }
static inline double min_c(double x, double c) { return x < c ? x : c; }

/* The quasi-static radial stress at the cavity wall (Pa) of the elastic-cracked-plastic cavity expansion
 * (docs/theory.md §4.1), its one home (fepen.laws.target.quasi_static_stress calls it):
 *     sigma_s = (Y/lam) [(2/alpha)(c/a)^(alpha lam) - (3 - lam)/3],   alpha = 6/(3 + 2 lam)
 * written as Y [(2/alpha) expm1(alpha lam ln(c/a))/lam + 1], the Tresca value Y [1 + 2 ln(c/a)] at lam = 0. */
double cavity_wall_stress(double Y, double lam, double ca) {
    double alpha = 6.0 / (3.0 + 2.0 * lam), L = log(ca);
    double g = lam == 0.0 ? alpha * L : expm1(alpha * lam * L) / lam;
    return Y * ((2.0 / alpha) * g + 1.0);
}

static double cavity_stress(const double *p, double ca) { return cavity_wall_stress(p[P_Y], p[P_LAM], ca); }

/* a point's speed along its outward normal, v . n (the one expression law_at_point and the loops' skip share) */
static inline double normal_speed(const double *vi, const double *ni) {
    return vi[0] * ni[0] + vi[1] * ni[1] + vi[2] * ni[2];
}

/* What the law needs beyond p[] that is the same at every point: computed once per call by law_constants */
typedef struct {
    double thk, sin_min, ref, whole, mu_s, mu_d, decay;
} LawConstants;

static LawConstants law_constants(const double *p) {
    LawConstants c;
    c.thk = p[P_THICKNESS];
    c.sin_min = sin(p[P_PHI_MIN]);
    c.ref = p[P_FREE_SURFACE] != 0.0 ? cavity_stress(p, p[P_C_OVER_A]) : 1.0;
    /* the free-surface stress where the plastic zone is whole (ca = c/a): what the rule below gives there */
    c.whole = p[P_GIVEN_SIGMA_S] != 0.0 ? p[P_SIGMA_S] * c.ref / c.ref : c.ref;
    c.mu_s = p[P_MU];
    c.mu_d = p[P_MU_DYNAMIC];
    c.decay = p[P_MU_DECAY];
    return c;
}

/* cos t for the field's modes: t less the nearest multiple of 2 pi (in two parts), then cos's Taylor series to
 * r^22, within 2e-12 on [-pi, pi] (libm's cos had been 90 % of a rigid run with a field: this is 3.5 times
 * faster) */
static inline double field_cos(double t) {
    const double turns = floor(t * 0.15915494309189535 + 0.5);
    const double r = (t - turns * 6.283185307179586) - turns * 2.4492935982947064e-16, z = r * r;
    double c = -1.0 / 1124000727777607680000.0;                 /* -1/22! */
    c = c * z + 1.0 / 2432902008176640000.0;                    /* 1/20! */
    c = c * z - 1.0 / 6402373705728000.0;
    c = c * z + 1.0 / 20922789888000.0;
    c = c * z - 1.0 / 87178291200.0;
    c = c * z + 1.0 / 479001600.0;
    c = c * z - 1.0 / 3628800.0;
    c = c * z + 1.0 / 40320.0;
    c = c * z - 1.0 / 720.0;
    c = c * z + 1.0 / 24.0;
    c = c * z - 0.5;
    return c * z + 1.0;
}

/* The concrete's strength factor at a target point x (3, m; §8.8): exp(s g(x) - s^2/2), g(x) = sqrt(2/N)
 * sum_j cos(k_j . x + phase_j) a Gaussian field of unit variance (the spectral representation), so the factor is
 * lognormal of mean 1; 1 without a field. A function of the point alone: the same on any rank, in any order.
 * Not inlined: inlined, its cos and exp changed how GCC compiled the law around it, and the plain concrete's
 * forces moved by an ulp (tests/unit/runs/test_batch.py holds them to the batch's bits). */
__attribute__((noinline)) static double field_factor(const double *p, const double *x) {
    const int32_t nm = (int32_t)p[P_FIELD_MODES];
    if (nm <= 0) return 1.0;
    const double *m = p + P_COUNT, s = p[P_FIELD_SIGMA];
    double g = 0.0;
    for (int32_t j = 0; j < nm; ++j)
        g += field_cos(m[4 * j] * x[0] + m[4 * j + 1] * x[1] + m[4 * j + 2] * x[2] + m[4 * j + 3]);
    return exp(s * sqrt(2.0 / nm) * g - 0.5 * s * s);
}

/* The numbers a law p holds: P_COUNT and its field's modes */
static inline int32_t law_length(const double *p) { return P_COUNT + 4 * (int32_t)p[P_FIELD_MODES]; }

/* The quasi-static stress sigma_s at height y (m; the face y = 0) of a point with surface radius rho (m), the face
 * cutting the cavity expansion's plastic zone (§8.4) when the law asks (the concrete's random field, §8.8, is
 * local_stress's) */
static inline double static_stress(const double *p, const LawConstants *c, double y, double radius) {
    double s = p[P_SIGMA_S];
    if (p[P_FREE_SURFACE] != 0.0) {
        /* L_e: the shortest distance to the block's front face, or its rear face when it has one */
        double depth = max_c(-y, 0.0), Le = c->thk >= 0.0 ? fmin(depth, max_c(c->thk - depth, 0.0)) : depth;
        double ca = fmin(p[P_C_OVER_A], 1.0 + Le / (p[P_SURFACE_RANGE] * max_c(radius, 1e-12)));
        if (ca == p[P_C_OVER_A]) s = c->whole;
        else s = p[P_GIVEN_SIGMA_S] != 0.0 ? p[P_SIGMA_S] * cavity_stress(p, ca) / c->ref : cavity_stress(p, ca);
    }
    return s;
}

/* sigma_s at the target point x (3, m): static_stress times the concrete's random field there (§8.8; without a
 * field, static_stress to the last bit): the nose's and the wall's one text */
static inline double local_stress(const double *p, const LawConstants *c, const double *x, double radius) {
    const double s = static_stress(p, c, x[1], radius);
    return p[P_FIELD_MODES] > 0.0 ? s * field_factor(p, x) : s;
}

/* The tunnel's wall at a point pressed into it (§8.7): elastic, p = (2G/a) delta, up to its reload limit
 * reload sigma_s + B rho0 u^2 (u: the point's outward speed, while it pushes outward); the limit and the
 * stiffness 2G/a */
static inline double wall_limit(const double *p, double s, double u) {
    double up = u > 0.0 ? u : 0.0;
    return p[P_RELOAD] * s + p[P_B] * p[P_DENSITY] * up * up;
}

static inline double wall_stiffness(const double *p, double a) { return p[P_WALL_SHEAR2] / max_c(a, 1e-12); }

/* a point's push into the wall (m): its penetration less a round-off's width (1e-9 of the radius), so that a body
 * on the wall it opened, centred to the last bit or not, carries nothing (the spring's force is continuous) */
#define WALL_TOL 1e-9
static inline double wall_push(const WallHit *wall) { return wall->delta - WALL_TOL * wall->a; }

/* The immersed fraction of a point's patch below the target's face (its first factor: the rear face's is
 * law_at_point's), its one expression */
static inline double immersed(const double *p, const double *xi, double ell) {
    return clip01(0.5 - (xi[1] + p[P_TOP]) / ell);
}

/* THE LAW AT ONE POINT (docs/theory.md §8), its one text: the single rigid path and the deformable load reach it
 * through point_forces below, the batched rigid shots (fepen/runs/rigid_batch.c) include this file and call it.
 * The point (x, v, n: 3 each; its patch area and ell = sqrt(area); top = immersed(p, x, ell), which the loops
 * have from their own test; its surface radius, meridian radius and sin phi0) under the law p (with c =
 * law_constants(p)); axis (3) or NULL. Writes the point's force f (3) and stress *sig only when it is loaded and
 * returns 1; returns 0 (f, *sig untouched) when it is not. */
static inline int law_at_point(const double *p, const LawConstants *c, const double *xi, const double *vi,
                               const double *ni, double area, double ell, double top, double radius, double Rm,
                               double sphi0, const double *axis, const WallHit *wall, const double *gauss, int32_t ng,
                               double *fi, double *sig) {
    double y = xi[1];
    double frac = top;
    if (p[P_LOWER] >= 0.0) frac *= clip01(0.5 + (y + p[P_LOWER]) / ell);
    if (!(frac > 0.0)) return 0;
    double vn = normal_speed(vi, ni), u = 0.0;
    int loaded;
    if (wall) { /* in the tunnel (§8.7): loaded while it faces the wall and is pressed into it, however it moves */
        u = vi[0] * wall->er[0] + vi[1] * wall->er[1] + vi[2] * wall->er[2];
        loaded = wall_push(wall) > 0.0 && ni[0] * wall->er[0] + ni[1] * wall->er[1] + ni[2] * wall->er[2] > 0.0;
    } else { /* the open face: loaded where it moves into the target, past the separation angle */
        double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        double sin_phi = speed > 0.0 ? vn / max_c(speed, 1e-300) : 0.0;
        loaded = sin_phi > SIN_TOL && vn > 0.0;
        /* the wake: moving backward, a point meets the open tunnel, not concrete */
        if (axis) loaded = loaded && (vi[0] * axis[0] + vi[1] * axis[1] + vi[2] * axis[2] > 0.0);
        if (p[P_SEPARATION] != 0.0) loaded = loaded && sin_phi > c->sin_min;
    }
    if (!loaded) return 0;
    const double s = local_stress(p, c, xi, radius);
    /* the nose: the cavity-expansion stress at any speed into the target (sigma_s is its static limit); the
     * wall: elastic up to its reload limit, so a body pressed into it at rest is held, and let go of as it leaves */
    double sg = (wall ? fmin(wall->k * wall_push(wall), wall_limit(p, s, u))
                      : s + p[P_B] * p[P_DENSITY] * vn * vn) * frac;
    const double vx = wall ? max_c(u, 0.0) : vn; /* the speed that throws the medium out at the crater */
    if (p[P_CRATER] == 2.0 && -y < p[P_K] * p[P_D]) { /* the splash-streamline energy balance (§8.3) */
        double rho = max_c(radius, 1e-12), l = (p[P_C_OVER_A] - 1.0) * rho, integral = 0.0;
        for (int32_t g = 0; g < ng; ++g) {
            double w = 0.5 * l * (gauss[g] + 1.0), q = rho / (rho + w);
            integral += 0.5 * l * gauss[ng + g] * (1.0 + w / Rm) * (1.0 + w * sphi0 / rho) * q * q * q * q;
        }
        double depth = max_c(-y, 0.0), Le = c->thk >= 0.0 ? fmin(depth, max_c(c->thk - depth, 0.0)) : depth;
        double e_kin = 0.5 * p[P_LOCK_DENSITY] * vx * vx * integral;
        double e_str = p[P_CRUSH_STRAIN] * p[P_Y] * (2.0 * rho * Le + Le * Le) / rho;
        if (e_kin - e_str >= 0.0) sg = 0.0;
    }
    *sig = sg;
    double pa = sg * area;
    fi[0] = -pa * ni[0];
    fi[1] = -pa * ni[1];
    fi[2] = -pa * ni[2];
    if (p[P_FRICTION] != 0.0 && c->mu_s > 0.0) { /* sliding friction, LS-DYNA's FS, FD, DC form (§8.4) */
        double vt[3] = {vi[0] - vn * ni[0], vi[1] - vn * ni[1], vi[2] - vn * ni[2]};
        double st = sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
        if (st > 1e-9) {
            double mu = (c->decay == 0.0 || c->mu_d == c->mu_s) ? c->mu_s
                                                                : c->mu_d + (c->mu_s - c->mu_d) * exp(-c->decay * st);
            double cf = mu * pa / st;
            fi[0] -= cf * vt[0];
            fi[1] -= cf * vt[1];
            fi[2] -= cf * vt[2];
        }
    }
    return 1;
}

/* 0 when the point can carry no load: it moves out of its surface's outside (law_at_point's vn > 0 at the nose,
 * the same function) and cannot be in the tunnel (ahead of the shoulder, or no tunnel), where the elastic wall
 * holds a point pressed into it however it moves. The loops skip the others before locating them in the tunnel
 * (a point's station does not depend on which points were located before it: no bit changes) */
static inline int may_load(const double *vi, const double *ni, const double *T, double xi) {
    return normal_speed(vi, ni) > 0.0 || (T && xi > T[T_XI_SH] && T[T_M] >= 1.0);
}

/* Where the point is in the tunnel T (NULL: no tunnel): TUNNEL_IN with its WallHit, TUNNEL_CLEAR (clear of the
 * wall: the law would not load it), or TUNNEL_OUT (not in the tunnel: the open face's law) */
static inline int wall_of(const double *T, TunnelEnd *e, const double *xi_point, double xi, double k,
                          WallHit *hit) {
    if (!T) return TUNNEL_OUT;
    int32_t kn, sec;
    double rho;
    const int at = tunnel_locate(T, e, xi_point, xi, 1, &hit->delta, hit->er, &kn, &sec, &rho);
    hit->a = T[T_A0];
    hit->k = k;
    return at;
}

/* A step's first stage, after the law: where the wall is pressed past its reload limit it yields, the plastic
 * cavity opened out to the radius at which the point's elastic push carries the limit (rho - limit k^-1, at the
 * point's nearest recorded station and sector, if wider than it is); pressed within it, the wall stays as it is
 * (§8.7). The radius a point asks for depends on that point alone (its place, speed and law), not on the
 * radii other points have just widened: the wall is the same whatever order, or rank, yields it. */
static void wall_yield(double *T, TunnelEnd *e, const double *p, const LawConstants *c, const double *xi_point,
                       const double *vi, double radius, double xi) {
    double delta, er[3], rho;
    int32_t kn, sec;
    if (tunnel_locate(T, e, xi_point, xi, 0, &delta, er, &kn, &sec, &rho) != TUNNEL_IN || kn < 0) return;
    const WallHit hit = {delta, {er[0], er[1], er[2]}, T[T_A0], wall_stiffness(p, T[T_A0])};
    const double u = vi[0] * er[0] + vi[1] * er[1] + vi[2] * er[2];
    const double limit = wall_limit(p, local_stress(p, c, xi_point, radius), u);
    tunnel_widen(T, kn, sec, rho - WALL_TOL * hit.a - limit / hit.k);
}

/* The law on k points, its one driver: point_forces's, and the rigid run's step's (fepen/runs/rigid_batch.c, which
 * includes this file). ell (k): each patch's sqrt(area) when given (NULL: taken here, the same bits); idx: NULL, or
 * room for k indices. The law is evaluated at the points that may load (may_load, not clear of the tunnel's wall, not
 * wholly above the face: the tests in that order, none of which changes another's answer), their forces into f
 * and stresses into sig, and the others left as they are: the caller zeroes them (point_forces: every point;
 * the step: at the points it loaded before). With idx the evaluated points' indices go into it, in order, and only
 * their forces are summed (the others are zero: a zero term changes no sum, and a sum from +0 is never -0); without
 * it every point's is. A call with T[T_COMMIT] set first records a station, then lets the wall yield where the
 * points press it past its reload limit (wall_yield), and clears the flag. Returns how many points it evaluated. */
__attribute__((noinline)) static int32_t law_points(int32_t k, const double *x, const double *v, const double *n,
                                                    const double *area, const double *ell, const double *radius,
                                                    const double *Rm, const double *sphi0, const double *axis,
                                                    const double *p, const double *gauss, int32_t ng, double *f,
                                                    double *sig, int32_t *idx, double *sums, const double *body_xi,
                                                    double *T) {
    const LawConstants c = law_constants(p);
    const int commit = T && T[T_COMMIT] != 0.0;
    if (commit) tunnel_record(T);
    TunnelEnd end;
    if (T) tunnel_end(T, &end);
    const double k_wall = T ? wall_stiffness(p, T[T_A0]) : 0.0;
    int32_t m = 0;
    for (int j = 0; j < SUM_COUNT; ++j) sums[j] = 0.0;
    for (int32_t i = 0; i < k; ++i) {
        double sg = 0.0;
        if (!may_load(v + 3 * i, n + 3 * i, T, T ? body_xi[i] : 0.0)) continue;
        WallHit hit;
        const int at = wall_of(T, &end, x + 3 * i, T ? body_xi[i] : 0.0, k_wall, &hit);
        if (at == TUNNEL_CLEAR) continue; /* in the tunnel, clear of its wall */
        const double ell_i = ell ? ell[i] : sqrt(area[i]);
        const double top = immersed(p, x + 3 * i, ell_i);
        if (!(top > 0.0)) continue; /* wholly above the face */
        if (!law_at_point(p, &c, x + 3 * i, v + 3 * i, n + 3 * i, area[i], ell_i, top, radius[i], Rm[i], sphi0[i],
                          axis, at == TUNNEL_IN ? &hit : NULL, gauss, ng, f + 3 * i, &sg))
            continue;
        if (sg > 0.0) {
            sums[SUM_LOADED] += 1.0;
            sums[SUM_AREA] += area[i];
        }
        sig[i] = sg;
        if (idx) idx[m] = i;
        m++;
    }
    const int32_t some = idx ? m : k; /* the points the loops below visit: idx's, or all */
    if (commit) {
        for (int32_t j = 0; j < some; ++j) {
            const int32_t i = idx ? idx[j] : j;
            if (sig[i] > 0.0) wall_yield(T, &end, p, &c, x + 3 * i, v + 3 * i, radius[i], body_xi[i]);
        }
        T[T_COMMIT] = 0.0;
    }
    for (int32_t j = 0; j < some; ++j) {
        const double *fi = f + 3 * (idx ? idx[j] : j);
        sums[SUM_FORCE] += fi[0];
        sums[SUM_FORCE + 1] += fi[1];
        sums[SUM_FORCE + 2] += fi[2];
    }
    return m;
}

/* k points; x, v, n (k, 3); area, radius, Rm, sphi0 (k); axis (3) or NULL; gauss: ng nodes then ng weights;
 * body_xi (k): each point's distance behind the tip in the body frame, and T: the tunnel (tunnel_kernel.c; NULL:
 * none, body_xi unread). A call with T[T_COMMIT] set (a step's first stage) first records a station, then
 * lets the wall yield where the points press it past its reload limit (wall_yield), and clears the flag.
 * Out: f (k, 3) and sig (k) (zero where not loaded), sums: force (3), loaded count, loaded area.
 * Returns the numbers of the law it read (law_length). */
int32_t point_forces(int32_t k, const double *x, const double *v, const double *n, const double *area,
                     const double *radius, const double *Rm, const double *sphi0, const double *axis,
                     const double *p, const double *gauss, int32_t ng, double *f, double *sig, double *sums,
                     const double *body_xi, double *T) {
    for (int32_t i = 0; i < k; ++i) {
        f[3 * i] = f[3 * i + 1] = f[3 * i + 2] = 0.0;
        sig[i] = 0.0;
    }
    law_points(k, x, v, n, area, NULL, radius, Rm, sphi0, axis, p, gauss, ng, f, sig, NULL, sums, body_xi, T);
    return law_length(p);
}

/* The strength factor of the law p's random field at k target points x (k, 3) into out (k); returns the numbers
 * of the law it read */
int32_t strength_field(int32_t k, const double *x, const double *p, double *out) {
    for (int32_t i = 0; i < k; ++i) out[i] = field_factor(p, x + 3 * i);
    return law_length(p);
}

/* The sectors of k points' offsets r (k, 3) about unit axes t (k, 3), S sectors: q as tunnel_locate takes it (the
 * polynomial, libm's atan2 near an edge) and q_exact from libm's atan2 alone (the tests: the two agree). */
void tunnel_sectors(int32_t k, const double *r, const double *t, int32_t S, int32_t *q, int32_t *q_exact) {
    for (int32_t i = 0; i < k; ++i) {
        const double *ti = t + 3 * i, *ri = r + 3 * i;
        double e1[3];
        const double n1sq = tunnel_e1(ti, e1);
        double u1[3] = {e1[0], e1[1], e1[2]};
        q[i] = tunnel_sector(ri, ti, e1, n1sq, S);
        const double n1 = sqrt(n1sq);
        for (int j = 0; j < 3; ++j) u1[j] /= n1;
        double e2[3] = {ti[1] * u1[2] - ti[2] * u1[1], ti[2] * u1[0] - ti[0] * u1[2], ti[0] * u1[1] - ti[1] * u1[0]};
        q_exact[i] = tunnel_sector_exact(tdot(ri, e2), tdot(ri, u1), S);
    }
}

/* Where k points x (k, 3) at body-axial distances xi (k) lie in the tunnel T as it is now (its shoulder and axis
 * set): clear[i] whether tunnel_locate calls it clear, located[i] whether it locates it without that test, and where located, its push delta[i] (m) and
 * distance from the axis rho[i] (m); for the tests (the clear test never skips a point the locate would find
 * pressed; the located distances against a curved tunnel's exact ones). */
void tunnel_probe(const double *T, int32_t k, const double *x, const double *xi, int32_t *clear, int32_t *located,
                  double *delta, double *rho) {
    TunnelEnd e, f;
    tunnel_end(T, &e);
    tunnel_end(T, &f);
    for (int32_t i = 0; i < k; ++i) {
        double er[3];
        int32_t kn, sec;
        double d0;
        clear[i] = tunnel_locate(T, &e, x + 3 * i, xi[i], 1, &d0, er, &kn, &sec, &d0) == TUNNEL_CLEAR;
        located[i] = tunnel_locate(T, &f, x + 3 * i, xi[i], 0, delta + i, er, &kn, &sec, rho + i) == TUNNEL_IN;
    }
}
