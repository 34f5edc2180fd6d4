/* The rigid run's RK4 step, single or batched (docs/theory.md §9): rigid_step advances one shot by one step for
 * fepen.runs.rigid.RigidRun.step (the single path) and rigid_stop_back takes an embedded stop back to V.a = 0 for
 * its stop rules, and rigid_batch runs many shots of one projectile in one call
 * (fepen/runs/batch.py), each shot's loop (one_shot: the same step, rk4, then the stop rules and the history maxima
 * as RigidRun advances it) with no Python per stage. The load points and the force sums are rigid_kernel.c's
 * rigid_points and force_moment (passed in as function pointers and called on all the points: they are
 * vectorised, so a point's rounding depends on its place in the array); the target law is target_kernel.c's
 * law_at_point and the stop rules events_kernel.c's penetration_rule, both included (the law built as that
 * file is built, a * b + c contracted alike). The glue between them (quaternions, omega, the crater scale, the
 * stage states, the work, the angular impulse, the history rows' depth and energy error) repeats the numpy
 * oracle's expressions (fepen.laws.rigid_body.RigidBody.rk4_step) operation by operation, in their order, built
 * without contracting a * b + c into one rounding (-ffp-contract=off, fepen.native), so that a step is bitwise
 * the oracle's. tests/unit/runs/test_rigid_step.py and test_batch.py hold them together. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "rigid_batch.h"

/* The law (target_kernel.c's law_points, point_forces's own driver, and law_at_point), built as the single path
 * builds target_kernel.c (a * b + c contracted as there) */
#pragma GCC push_options
#pragma GCC optimize("fp-contract=fast")
#include "../laws/target_kernel.c"

#pragma GCC pop_options

/* the stop rules (penetration_rule), built here without contraction as there */
#include "events_kernel.c"

typedef void (*points_fn)(int32_t, const double *, const double *, const double *, const double *,
                          const double *, const double *, double *, double *, double *, double *);
typedef void (*moment_fn)(int32_t, const double *, const double *, double *);

/* rigid_kernel.c's force_moment on the points up to the last one loaded (idx is increasing), rounded up to a
 * multiple of 16 (or all k): the function is vectorised by blocks of points from the first (8 doubles wide at
 * most), and a point's rounding depends on its place in its block, so every point keeps its place, and the
 * points left out carry zero forces, whose terms change no sum. Then f zeroed again at idx. */
static void moment_points(moment_fn moment, int32_t k, int32_t m, const int32_t *idx, const double *arm, double *f,
                          double *FM) {
    int32_t n = m > 0 ? idx[m - 1] + 1 : 0;
    n = (n + 15) / 16 * 16;
    moment(n < k ? n : k, arm, f, FM);
    for (int32_t j = 0; j < m; ++j) memset(f + 3 * idx[j], 0, 3 * sizeof(double));
}

typedef struct {
    int32_t k, ng;
    const double *r0, *N0, *area, *ell, *radius, *Rm, *sphi0, *gauss;
    points_fn points;
    moment_fn moment;
    double at[Y_COUNT], R[9], w[3]; /* the state whose points x, v, n, arm hold (at[Y_QUAT] = 2: none), R, omega */
    double *x, *v, *n, *arm, *f; /* scratch (f zero outside the points a law call loads) */
    int32_t *idx;
    const double *xi; /* each point's distance behind the tip, body frame */
    double *T, *tunnel, *sg; /* the shot's tunnel (NULL: none), its buffer, the loaded points' stresses */
    int32_t cap, sectors;
} Body;

/* numpy's dot of two 3- or 4-vectors: from 0, left to right */
static double dot3(const double *a, const double *b) { return ((0.0 + a[0] * b[0]) + a[1] * b[1]) + a[2] * b[2]; }

static void quat_to_matrix(const double *q, double *R) {
    double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - w * z); R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z); R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y); R[7] = 2 * (y * z + w * x); R[8] = 1 - 2 * (x * x + y * y);
}

/* M (3, 3) row-major times a, and its transpose times a, as numpy's matmul sums them */
static void matvec(const double *M, const double *a, double *out) {
    for (int i = 0; i < 3; ++i) out[i] = ((0.0 + M[3 * i] * a[0]) + M[3 * i + 1] * a[1]) + M[3 * i + 2] * a[2];
}
static void matTvec(const double *M, const double *a, double *out) {
    for (int i = 0; i < 3; ++i) out[i] = ((0.0 + M[i] * a[0]) + M[3 + i] * a[1]) + M[6 + i] * a[2];
}

/* omega = R (I^-1 (R^T L)) */
static void omega_of(const double *R, const double *Iinv, const double *L, double *w) {
    double a[3], b[3];
    matTvec(R, L, a);
    matvec(Iinv, a, b);
    matvec(R, b, w);
}

static double norm4(const double *q) {
    return sqrt((((0.0 + q[0] * q[0]) + q[1] * q[1]) + q[2] * q[2]) + q[3] * q[3]);
}

/* the load points of state y (x, v, n, arm into the body's scratch), R and omega; kept for the next call with
 * the same state (a step's end state: the stop rules', then the next step's first stage, as RigidBody.at) */
static void points_at(Body *b, const double *sp, const double *y, double *R, double *w) {
    if (memcmp(b->at, y, sizeof b->at) == 0) {
        memcpy(R, b->R, sizeof b->R);
        memcpy(w, b->w, sizeof b->w);
        return;
    }
    quat_to_matrix(y + Y_QUAT, R);
    omega_of(R, sp + S_IINV, y + Y_MOMENTUM, w);
    double small[18];
    memcpy(small, R, 9 * sizeof(double));
    memcpy(small + 9, y, 3 * sizeof(double));
    memcpy(small + 12, y + Y_VELOCITY, 3 * sizeof(double));
    memcpy(small + 15, w, 3 * sizeof(double));
    b->points(b->k, b->r0, b->N0, small, small + 9, small + 12, small + 15, b->x, b->v, b->n, b->arm);
    memcpy(b->at, y, sizeof b->at);
    memcpy(b->R, R, sizeof b->R);
    memcpy(b->w, w, sizeof b->w);
}

/* a stage's point forces, velocities and normals (3 (k, 3) arrays) into out, for Python's wear (Wear.stage) */
static void stage_points(const Body *b, double *out) {
    const size_t size = 3 * (size_t)b->k * sizeof(double);
    memcpy(out, b->f, size);
    memcpy(out + 3 * (size_t)b->k, b->v, size);
    memcpy(out + 6 * (size_t)b->k, b->n, size);
}

/* RigidBody.derivative with RigidRun.force_fn: dy (Y_COUNT), the force and moment, the power; loaded, area; stage
 * (NULL: none): the point forces, velocities and normals (stage_points) */
static void derivative(Body *b, const double *sp, const double *law, const double *y, double *dy, double *FM,
                       double *power, double *loaded, double *area, double *stage) {
    double R[9], w[3], tip[3], axis[3], sums[SUM_COUNT];
    points_at(b, sp, y, R, w);
    matvec(R, sp + S_TIP, tip);
    for (int j = 0; j < 3; ++j) tip[j] = y[j] + tip[j];
    for (int j = 0; j < 3; ++j) axis[j] = -R[3 * j + 1];
    if (b->T) { /* RigidRun.force_fn: the shoulder and the axis now, for the tunnel */
        double sh[3];
        matvec(R, sp + S_SHOULDER, sh);
        for (int j = 0; j < 3; ++j) {
            b->T[T_CS + j] = y[j] + sh[j];
            b->T[T_TS + j] = axis[j];
        }
    }
    int32_t m = law_points(b->k, b->x, b->v, b->n, b->area, b->ell, b->radius, b->Rm, b->sphi0, axis, law,
                           b->gauss, b->ng, b->f, b->sg, b->idx, sums, b->xi, b->T);
    if (sp[S_CRATER] != 0.0) { /* ForrestalCrater.scale(-tip[1], -(total . axis)) */
        double depth = -tip[1], axial = -dot3(sums, axis), scale = 1.0;
        if (!(depth >= sp[S_CRATER_KD] || axial <= 0.0)) scale = fmax(depth, 0.0) * sp[S_CRATER_C] / axial;
        for (int32_t j = 0; j < m; ++j) {
            double *fi = b->f + 3 * b->idx[j];
            fi[0] *= scale; fi[1] *= scale; fi[2] *= scale;
        }
    }
    *loaded = sums[SUM_LOADED];
    *area = sums[SUM_AREA];
    if (stage) stage_points(b, stage);
    moment_points(b->moment, b->k, m, b->idx, b->arm, b->f, FM);
    double q[4] = {y[Y_QUAT], y[Y_QUAT + 1], y[Y_QUAT + 2], y[Y_QUAT + 3]};
    double w1 = 0.0, x1 = w[0], y1 = w[1], z1 = w[2], w2 = q[0], x2 = q[1], y2 = q[2], z2 = q[3];
    for (int j = 0; j < 3; ++j) dy[Y_CENTRE + j] = y[Y_VELOCITY + j];
    dy[Y_QUAT] = 0.5 * (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2);
    dy[Y_QUAT + 1] = 0.5 * (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2);
    dy[Y_QUAT + 2] = 0.5 * (w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2);
    dy[Y_QUAT + 3] = 0.5 * (w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2);
    for (int j = 0; j < 3; ++j) dy[Y_VELOCITY + j] = FM[j] / sp[S_MASS];
    for (int j = 0; j < 3; ++j) dy[Y_MOMENTUM + j] = FM[3 + j];
    *power = dot3(FM, y + Y_VELOCITY) + dot3(FM + 3, w);
}

/* RigidBody.rk4_step: y advanced by dt in place, the step's numbers into out (STEP_: the force at its start, the
 * work, the angular impulse about O, the last stage's loaded points and area); stages (NULL: none) the four stages'
 * point forces, velocities and normals (4 x 3 (k, 3)) */
static void rk4(Body *b, const double *sp, const double *law, double *y, double dt, double *out, double *stages) {
    double k[4][Y_COUNT], s[Y_COUNT], FM[6], P, work = 0.0, ang[3] = {0.0, 0.0, 0.0};
    static const double c[4] = {0.0, 0.5, 0.5, 1.0}, wt[4] = {1.0, 2.0, 2.0, 1.0};
    for (int i = 0; i < 4; ++i) {
        if (i) {
            double cdt = c[i] * dt;
            for (int j = 0; j < Y_COUNT; ++j) s[j] = y[j] + cdt * k[i - 1][j];
        } else {
            memcpy(s, y, sizeof s);
            if (b->T) b->T[T_COMMIT] = 1.0; /* RigidRun.step: the step's first stage records the tunnel */
        }
        derivative(b, sp, law, s, k[i], FM, &P, out + STEP_LOADED, out + STEP_AREA,
                   stages ? stages + (size_t)i * 9 * (size_t)b->k : NULL);
        if (i == 0) memcpy(out + STEP_FORCE, FM, 3 * sizeof(double));
        work += wt[i] * P;
        const double cr[3] = {s[1] * FM[2] - s[2] * FM[1], s[2] * FM[0] - s[0] * FM[2], s[0] * FM[1] - s[1] * FM[0]};
        for (int j = 0; j < 3; ++j) ang[j] += wt[i] * (FM[3 + j] + cr[j]); /* the moment about O (np.cross) */
    }
    double h = dt / 6.0;
    for (int j = 0; j < Y_COUNT; ++j) y[j] = y[j] + h * (((k[0][j] + 2 * k[1][j]) + 2 * k[2][j]) + k[3][j]);
    double nq = norm4(y + Y_QUAT);
    for (int j = Y_QUAT; j < Y_QUAT + 4; ++j) y[j] /= nq;
    out[STEP_WORK] = h * work;
    for (int j = 0; j < 3; ++j) out[STEP_ANGULAR + j] = h * ang[j];
}

/* the axis (tail to nose) of state y: R (0, -1, 0) */
static void axis_of(const double *y, double *a) {
    double R[9], down[3] = {0.0, -1.0, 0.0};
    quat_to_matrix(y + Y_QUAT, R);
    matvec(R, down, a);
}

/* a history row's depth of the tip (mm) and energy error at state y (RigidRun.snapshot) */
static void row_of(const double *sp, const double *y, double work, double *nose, double *error) {
    double R[9], w[3], tip[3];
    quat_to_matrix(y + Y_QUAT, R);
    omega_of(R, sp + S_IINV, y + Y_MOMENTUM, w);
    matvec(R, sp + S_TIP, tip);
    *nose = -(y[Y_CENTRE + 1] + tip[1]) * 1e3;
    double ke = 0.5 * sp[S_MASS] * dot3(y + Y_VELOCITY, y + Y_VELOCITY) + 0.5 * dot3(w, y + Y_MOMENTUM),
           ke0 = sp[S_KE0];
    double scale = ke0, aw = fabs(work);
    if (aw > scale) scale = aw;
    if (ke > scale) scale = ke;
    if (1e-300 > scale) scale = 1e-300;
    *error = fabs((((ke + 0.0) + 0.0) - ke0 - work) - 0.0) / scale;
}

/* An embedded stop's interpolation (RigidRun.stop_rules, the batch's and the single path's): when V.a <= 0 at y,
 * y is taken back along the step from prev (Y_COUNT each) to where the speed along the axis vanishes, V.a = 0 by
 * linear interpolation, its quaternion normalised again; lam: the fraction of the step kept (1 when y stays).
 * Returns 1 when it moved y, else 0. */
int32_t rigid_stop_back(const double *prev, double *y, double *lam) {
    double a[3], ap[3];
    axis_of(y, a);
    *lam = 1.0;
    if (!(dot3(y + Y_VELOCITY, a) <= 0.0)) return 0;
    axis_of(prev, ap);
    const double a0 = dot3(prev + Y_VELOCITY, ap), a1 = dot3(y + Y_VELOCITY, a);
    const double l = a0 - a1 > 0.0 ? a0 / (a0 - a1) : 1.0;
    for (int j = 0; j < Y_COUNT; ++j) y[j] = prev[j] + l * (y[j] - prev[j]);
    const double nq = norm4(y + Y_QUAT);
    for (int j = Y_QUAT; j < Y_QUAT + 4; ++j) y[j] /= nq;
    *lam = l;
    return 1;
}

static int finite13(const double *y) {
    for (int j = 0; j < Y_COUNT; ++j)
        if (!isfinite(y[j])) return 0;
    return 1;
}

/* One shot from y (Y_COUNT) at t = 0 to its end or stop; y becomes the final state. */
static void one_shot(Body *b, const double *sp, const double *law, double *y, double *res) {
    b->at[Y_QUAT] = 2.0; /* no unit quaternion: nothing kept from the last shot (another inertia) */
    b->T = NULL;
    if (sp[S_TUNNEL] != 0.0 && b->tunnel) { /* fepen.laws.tunnel.Tunnel's header, empty */
        double *T = b->T = b->tunnel;
        for (int j = 0; j < T_HEADER; ++j) T[j] = 0.0;
        T[T_CAP] = b->cap; T[T_S] = b->sectors; T[T_SPACING] = sp[S_SPACING]; T[T_XI_SH] = sp[S_XI_SH];
        T[T_A0] = sp[S_A0];
    }
    double t = 0.0, work = 0.0, next = 0.0, prev[Y_COUNT], R[9], w[3];
    double max_nose = -INFINITY, max_error = -INFINITY, rows = 0.0;
    int64_t steps = 0;
    int outcome = 0, status = 0;
    int32_t entered = 0;
    const double dt = sp[S_DT], interval = sp[S_HISTORY], thk = sp[S_THICKNESS];
    double F[3] = {0.0, 0.0, 0.0}; /* a row's force: at the start of the last step (at t = 0 the initial one) */
    if (interval > 0.0) {
        double dy[Y_COUNT], FM[6], P, loaded, area;
        derivative(b, sp, law, y, dy, FM, &P, &loaded, &area, NULL);
        memcpy(F, FM, sizeof F);
    }
    while (outcome == 0 && t < sp[S_HARD_END]) {
        if (interval > 0.0 && t >= next) { /* History.write: a row, then the clock */
            double nose, error;
            row_of(sp, y, work, &nose, &error);
            /* Results.finite_row of the row: what of it is not finite when these are */
            if (!isfinite(nose) || !isfinite(error) || !isfinite(work) || !isfinite(F[0]) || !isfinite(F[1]) ||
                !isfinite(F[2])) { status = 1; break; }
            if (rows == 0.0 || nose > max_nose) max_nose = nose;
            if (rows == 0.0 || error > max_error) max_error = error;
            rows += 1.0;
            while (next <= t) { /* Clock.advance: a clock far behind (an interval far below the step) jumps */
                double behind = (t - next) / interval;
                if (behind > 1000.0) next += floor(behind) * interval;
                next += interval;
            }
        }
        memcpy(prev, y, sizeof prev);
        double out[STEP_COUNT];
        rk4(b, sp, law, y, dt, out, NULL);
        memcpy(F, out + STEP_FORCE, sizeof F);
        work += out[STEP_WORK];
        t += dt;
        steps += 1;
        if (!finite13(y)) { status = 1; break; }
        /* Run.stop_rules: the extent of the load points, then StopRules.penetration */
        points_at(b, sp, y, R, w);
        double ymin = b->x[1], ymax = b->x[1];
        for (int32_t i = 1; i < b->k; ++i) {
            double yi = b->x[3 * i + 1];
            if (yi < ymin) ymin = yi;
            if (yi > ymax) ymax = yi;
        }
        double a[3];
        axis_of(y, a);
        outcome = penetration_rule(ymin, ymax, y + Y_VELOCITY, a, sp[S_MASS], sp[S_KE0], thk,
                                   sp[S_UNTIL_STOPPED] != 0.0, sp[S_STOP_ENERGY], &entered);
        /* RigidRun.stop_rules: back to where V.a vanishes */
        double lam;
        if (outcome == OUTCOME_EMBEDDED && rigid_stop_back(prev, y, &lam)) t -= (1.0 - lam) * dt;
    }
    res[R_T] = t;
    res[R_STEPS] = (double)steps;
    res[R_OUTCOME] = outcome;
    res[R_WORK] = work;
    res[R_ENTERED] = entered;
    res[R_MAX_NOSE] = max_nose;
    res[R_MAX_ERROR] = max_error;
    res[R_ROWS] = rows;
    res[R_STATUS] = status;
}

/* n shots sharing k load points (r0, N0: body-frame arms and normals; area, ell = sqrt(area), radius, Rm,
 * sphi0: the law's per-point constants; gauss: ng nodes then ng weights; points, moment: rigid_kernel.c's
 * rigid_points and force_moment). Per shot: sp (n, S_COUNT), laws (n, nlaw) the TargetLaw's numbers (P_COUNT and
 * its random field's modes, padded to the longest), y (n, Y_COUNT) the initial state, overwritten by the final one;
 * res (n, R_COUNT). Returns S_COUNT * 10000 + R_COUNT * 100 + nlaw (the caller checks the layouts), or -1 when
 * the scratch is not allocated or a law is longer than nlaw. */
int32_t rigid_batch(int32_t n, int32_t k, const double *r0, const double *N0, const double *area, const double *ell,
                    const double *radius, const double *Rm, const double *sphi0, const double *gauss, int32_t ng,
                    void *points, void *moment, const double *sp, const double *laws, int32_t nlaw, double *y,
                    double *res, const double *xi, int32_t cap, int32_t sectors, double *tunnels) {
    Body b = {k, ng, r0, N0, area, ell, radius, Rm, sphi0, gauss, (points_fn)points, (moment_fn)moment, {0}, {0},
              {0}, NULL, NULL, NULL, NULL, NULL, NULL, xi, NULL, NULL, NULL, cap, sectors};
    size_t kk = (size_t)(k > 0 ? k : 1);
    double *scratch = calloc(16 * kk, sizeof(double));
    int32_t *idx = malloc(sizeof(int32_t) * kk);
    int32_t fits = nlaw >= P_COUNT;
    for (int32_t s = 0; fits && s < n; ++s) fits = law_length(laws + (size_t)s * nlaw) <= nlaw;
    if (!scratch || !idx || !fits) {
        free(scratch);
        free(idx);
        return -1;
    }
    b.x = scratch; b.v = b.x + 3 * k; b.n = b.v + 3 * k; b.arm = b.n + 3 * k; b.f = b.arm + 3 * k; b.idx = idx;
    b.sg = b.f + 3 * k;
    const size_t tlen = (size_t)(T_HEADER + (int64_t)cap * (T_STATION + sectors));
    for (int32_t s = 0; s < n; ++s) {
        b.tunnel = tunnels ? tunnels + (size_t)s * tlen : NULL; /* each shot's own: its final tunnel stays */
        one_shot(&b, sp + (size_t)s * S_COUNT, laws + (size_t)s * nlaw, y + (size_t)s * Y_COUNT,
                res + (size_t)s * R_COUNT);
    }
    free(scratch);
    free(idx);
    return S_COUNT * 10000 + R_COUNT * 100 + nlaw;
}

/* One shot's one RK4 step (the single path's, fepen.runs.rigid.RigidRun.step; rk4, the batch's step): the
 * arguments as rigid_batch's for one shot, y (Y_COUNT) advanced in place, T the shot's tunnel (NULL: none; its
 * shoulder, axis and commit flag are set here), out (STEP_COUNT) the step's numbers, stages (NULL: none) the four
 * stages' point forces, velocities and normals (4 x 3 (k, 3)). Returns S_COUNT * 100 + STEP_COUNT (the caller
 * checks the layouts), or -1 when the scratch is not allocated. */
int32_t rigid_step(int32_t k, const double *r0, const double *N0, const double *area, const double *ell,
                   const double *radius, const double *Rm, const double *sphi0, const double *gauss, int32_t ng,
                   void *points, void *moment, const double *sp, const double *law, double *y, const double *xi,
                   double *T, double *out, double *stages) {
    Body b = {k, ng, r0, N0, area, ell, radius, Rm, sphi0, gauss, (points_fn)points, (moment_fn)moment, {0}, {0},
              {0}, NULL, NULL, NULL, NULL, NULL, NULL, xi, T, T, NULL, 0, 0};
    size_t kk = (size_t)(k > 0 ? k : 1);
    double *scratch = calloc(16 * kk, sizeof(double));
    int32_t *idx = malloc(sizeof(int32_t) * kk);
    if (!scratch || !idx) {
        free(scratch);
        free(idx);
        return -1;
    }
    b.x = scratch; b.v = b.x + 3 * k; b.n = b.v + 3 * k; b.arm = b.n + 3 * k; b.f = b.arm + 3 * k; b.idx = idx;
    b.sg = b.f + 3 * k;
    b.at[Y_QUAT] = 2.0; /* no state kept */
    rk4(&b, sp, law, y, sp[S_DT], out, stages);
    free(scratch);
    free(idx);
    return S_COUNT * 100 + STEP_COUNT;
}

/* The batch's law on one set of points, for the tests against point_forces: f (k, 3) (zero where not loaded)
 * and sums (5) as point_forces gives them. */
void batch_law(int32_t k, const double *x, const double *v, const double *n, const double *area, const double *ell,
               const double *radius, const double *Rm, const double *sphi0, const double *axis, const double *p,
               const double *gauss, int32_t ng, double *f, double *sums) {
    int32_t *idx = malloc(sizeof(int32_t) * (size_t)(k > 0 ? k : 1));
    double *sg = malloc(sizeof(double) * (size_t)(k > 0 ? k : 1));
    if (idx && sg) {
        for (int32_t i = 0; i < 3 * k; ++i) f[i] = 0.0;
        law_points(k, x, v, n, area, ell, radius, Rm, sphi0, axis, p, gauss, ng, f, sg, idx, sums, NULL, NULL);
    }
    free(idx);
    free(sg);
}
