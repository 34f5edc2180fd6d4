/* The target law (docs/theory.md §8) on surface points, its one home: immersion, tunnel stress, wake,
 * separation, free surface, onset, energy crater, sliding friction, and the tunnel's wall (tunnel_kernel.c), at
 * one point (law_at_point), and on k
 * points (point_forces, which fepen.laws.target.load_on_points calls through fepen.native before its
 * linear-crater scaling). tests/unit/laws/test_target_kernel.py checks it against an independent numpy
 * oracle of the equations and against their limits. Built once per machine, called by ctypes. */
#include <math.h>
#include <stdint.h>

/* p[]: the TargetLaw as numbers, in this order */
enum { P_DENSITY, P_Y, P_E, P_T, P_LAM, P_SIGMA_S, P_B, P_THICKNESS /* < 0: none */, P_CRATER /* 2: energy */,
       P_K, P_D, P_SEPARATION, P_PHI_MIN, P_FREE_SURFACE, P_FRICTION, P_MU, P_MU_DYNAMIC, P_MU_DECAY,
       P_LOCK_DENSITY, P_CRUSH_STRAIN, P_C_OVER_A, P_GIVEN_SIGMA_S, P_ONSET,
       P_TOP /* the material's own faces in a block of layers */, P_LOWER /* < 0: none */,
       P_SURFACE_RANGE /* the free face's reach in plastic-zone widths */,
       P_ONSET_SPEED /* sigma_s develops over the first onset_speed of a point's normal speed (m/s); 0: at once */,
       P_FACE_ONSET /* the same on the open face (m/s): min(onset_speed, ONSET_FRACTION x striking speed) */,
       P_COUNT };

#define SIN_TOL 1e-9

#include "tunnel_kernel.c"

/* A point in the tunnel (tunnel_kernel.c): its penetration of the wall (m) and the outward unit vector */
typedef struct {
    double delta, er[3];
} WallHit;

static double clip01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

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
    double thk, sin_min, sin_onset, ref, whole, mu_s, mu_d, decay;
} LawConstants;

static LawConstants law_constants(const double *p) {
    LawConstants c;
    c.thk = p[P_THICKNESS];
    c.sin_min = sin(p[P_PHI_MIN]);
    c.sin_onset = sin(p[P_ONSET]);
    c.ref = p[P_FREE_SURFACE] != 0.0 ? cavity_stress(p, p[P_C_OVER_A]) : 1.0;
    /* the free-surface stress where the plastic zone is whole (ca = c/a): what the rule below gives there */
    c.whole = p[P_GIVEN_SIGMA_S] != 0.0 ? p[P_SIGMA_S] * c.ref / c.ref : c.ref;
    c.mu_s = p[P_MU];
    c.mu_d = p[P_MU_DYNAMIC];
    c.decay = p[P_MU_DECAY];
    return c;
}

/* THE LAW AT ONE POINT (docs/theory.md §8), its one text: the single rigid path and the deformable load reach it
 * through point_forces below, the batched rigid shots (fepen/runs/rigid_batch.c) include this file and call it.
 * The point (x, v, n: 3 each; its patch area and ell = sqrt(area); its surface radius, meridian radius and
 * sin phi0) under the law p (with c = law_constants(p)); axis (3) or NULL. Writes the point's force f (3) and
 * stress *sig only when it is loaded and returns 1; returns 0 (f, *sig untouched) when it is not. */
static inline int law_at_point(const double *p, const LawConstants *c, const double *xi, const double *vi,
                               const double *ni, double area, double ell, double radius, double Rm, double sphi0,
                               const double *axis, const WallHit *wall, const double *gauss, int32_t ng, double *fi,
                               double *sig) {
    double y = xi[1];
    double frac = clip01(0.5 - (y + p[P_TOP]) / ell);
    if (p[P_LOWER] >= 0.0) frac *= clip01(0.5 + (y + p[P_LOWER]) / ell);
    if (wall) frac *= clip01(1.0 + wall->delta / ell); /* in the tunnel: the part of the patch at its wall */
    if (!(frac > 0.0)) return 0;
    double vn = normal_speed(vi, ni);
    double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
    double sin_phi = speed > 0.0 ? vn / fmax(speed, 1e-300) : 0.0, u = 0.0;
    int loaded;
    if (wall) { /* in the tunnel (§8.7): loaded while it faces the wall and pushes it outward */
        u = vi[0] * wall->er[0] + vi[1] * wall->er[1] + vi[2] * wall->er[2];
        loaded = u > 0.0 && ni[0] * wall->er[0] + ni[1] * wall->er[1] + ni[2] * wall->er[2] > 0.0;
    } else {
        loaded = sin_phi > SIN_TOL;
        /* the wake: moving backward, a point meets the open tunnel, not concrete */
        if (axis) loaded = loaded && (vi[0] * axis[0] + vi[1] * axis[1] + vi[2] * axis[2] > 0.0);
        if (p[P_SEPARATION] != 0.0) loaded = loaded && sin_phi > c->sin_min;
    }
    if (!loaded || !(vn > 0.0)) return 0;
    /* L_e: the shortest distance to the block's front face, or its rear face when it has one */
    double depth = fmax(-y, 0.0), Le = c->thk >= 0.0 ? fmin(depth, fmax(c->thk - depth, 0.0)) : depth;
    double s = p[P_SIGMA_S];
    if (p[P_FREE_SURFACE] != 0.0) {
        double ca = fmin(p[P_C_OVER_A], 1.0 + Le / (p[P_SURFACE_RANGE] * fmax(radius, 1e-12)));
        if (ca == p[P_C_OVER_A]) s = c->whole;
        else s = p[P_GIVEN_SIGMA_S] != 0.0 ? p[P_SIGMA_S] * cavity_stress(p, ca) / c->ref : cavity_stress(p, ca);
    }
    if (!wall && p[P_ONSET] > 0.0) s *= fmin(sin_phi / c->sin_onset, 1.0);
    /* at vanishing speed (§8.7): sigma_s develops over the first onset_speed of the point's speed into the target
     * (its normal speed; at the tunnel's wall its outward speed), so a body coming to rest is not loaded by the
     * whole rate-independent stress on every point that happens to face its last motion */
    const double onset_speed = wall ? p[P_ONSET_SPEED] : p[P_FACE_ONSET];
    if (onset_speed > 0.0) s *= fmin((wall ? u : vn) / onset_speed, 1.0);
    double sg = (s + p[P_B] * p[P_DENSITY] * vn * vn) * frac;
    if (p[P_CRATER] == 2.0 && -y < p[P_K] * p[P_D]) { /* the splash-streamline energy balance (§8.3) */
        double rho = fmax(radius, 1e-12), l = (p[P_C_OVER_A] - 1.0) * rho, integral = 0.0;
        for (int32_t g = 0; g < ng; ++g) {
            double w = 0.5 * l * (gauss[g] + 1.0), q = rho / (rho + w);
            integral += 0.5 * l * gauss[ng + g] * (1.0 + w / Rm) * (1.0 + w * sphi0 / rho) * q * q * q * q;
        }
        double e_kin = 0.5 * p[P_LOCK_DENSITY] * vn * vn * integral;
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

/* 1 when the point's patch lies wholly above the target's face (law_at_point's immersed fraction is 0 there,
 * whatever else holds): the loops skip it before locating it in the tunnel, which changes no bit */
static inline int above_face(const double *p, const double *xi, double ell) {
    return !(clip01(0.5 - (xi[1] + p[P_TOP]) / ell) > 0.0);
}

/* 1 when the point moves into its surface's outside (law_at_point's vn > 0, the same function): no other point
 * is loaded, in the tunnel or not, so the loops skip the others before locating them in the tunnel (half of a
 * shank's points; the station a point is located at does not depend on which points were located before it: no
 * bit changes) */
static inline int moving_into(const double *vi, const double *ni) { return normal_speed(vi, ni) > 0.0; }

/* The point's wall, when it is in the tunnel T (NULL: no tunnel): the WallHit, or NULL */
static inline const WallHit *wall_of(const double *T, TunnelEnd *e, const double *xi_point, double xi,
                                     WallHit *hit) {
    if (!T) return 0;
    int32_t kn, sec;
    double rho;
    if (!tunnel_locate(T, e, xi_point, xi, &hit->delta, hit->er, &kn, &sec, &rho)) return 0;
    return hit;
}

/* k points; x, v, n (k, 3); area, radius, Rm, sphi0 (k); axis (3) or NULL; gauss: ng nodes then ng weights;
 * body_xi (k): each point's distance behind the tip in the body frame, and T: the tunnel (tunnel_kernel.c; NULL:
 * none, body_xi unread). A call with T[T_COMMIT] set (a step's first stage) first records a station, then
 * pushes the wall out to the points it loads, and clears the flag.
 * Out: f (k, 3) and sig (k) (zero where not loaded), sums: force (3), loaded count, loaded area.
 * Returns P_COUNT. */
int32_t point_forces(int32_t k, const double *x, const double *v, const double *n, const double *area,
                     const double *radius, const double *Rm, const double *sphi0, const double *axis,
                     const double *p, const double *gauss, int32_t ng, double *f, double *sig, double *sums,
                     const double *body_xi, double *T) {
    const LawConstants c = law_constants(p);
    const int commit = T && T[T_COMMIT] != 0.0;
    if (commit) tunnel_record(T);
    TunnelEnd end;
    if (T) tunnel_end(T, &end);
    for (int j = 0; j < 5; ++j) sums[j] = 0.0;
    for (int32_t i = 0; i < k; ++i) {
        double *fi = f + 3 * i;
        fi[0] = fi[1] = fi[2] = 0.0;
        sig[i] = 0.0;
        const double ell = sqrt(area[i]);
        if (above_face(p, x + 3 * i, ell) || !moving_into(v + 3 * i, n + 3 * i)) continue;
        WallHit hit;
        const WallHit *wall = wall_of(T, &end, x + 3 * i, T ? body_xi[i] : 0.0, &hit);
        if (law_at_point(p, &c, x + 3 * i, v + 3 * i, n + 3 * i, area[i], ell, radius[i], Rm[i], sphi0[i],
                         axis, wall, gauss, ng, fi, sig + i) && sig[i] > 0.0) {
            sums[3] += 1.0;
            sums[4] += area[i];
        }
    }
    if (commit) {
        for (int32_t i = 0; i < k; ++i)
            if (sig[i] > 0.0) tunnel_expand(T, &end, x + 3 * i, body_xi[i]);
        T[T_COMMIT] = 0.0;
    }
    for (int32_t i = 0; i < k; ++i) {
        sums[0] += f[3 * i];
        sums[1] += f[3 * i + 1];
        sums[2] += f[3 * i + 2];
    }
    return P_COUNT;
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
