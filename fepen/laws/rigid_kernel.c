/* The rigid body's load points in one pass (fepen/laws/rigid_body.py, docs/theory.md §9): world positions,
 * velocities and normals from the body-frame arms and the state, and the force and moment sums. The numpy
 * expressions of RigidBody stay the reference; tests/unit/laws/test_rigid_kernel.py holds the two together.
 * Built once per machine, called by ctypes: a rigid shot evaluates these some 600 times, on ~1000 points. */
#include <stdint.h>

#include "rigid_kernel.h"

/* k points; r0, N0 (k, 3) body-frame arms and normals; R (3, 3) row-major; c, V, w (3): centre, velocity,
 * angular velocity (world). Out (k, 3): x = c + R r0, v = V + w x (R r0), n = R N0, arm = R r0. */
void rigid_points(int32_t k, const double *r0, const double *N0, const double *R, const double *c,
                  const double *V, const double *w, double *x, double *v, double *n, double *arm) {
    for (int32_t i = 0; i < k; ++i) {
        const double *r = r0 + 3 * i, *m = N0 + 3 * i;
        double a[3], b[3];
        for (int j = 0; j < 3; ++j) {
            a[j] = R[3 * j] * r[0] + R[3 * j + 1] * r[1] + R[3 * j + 2] * r[2];
            b[j] = R[3 * j] * m[0] + R[3 * j + 1] * m[1] + R[3 * j + 2] * m[2];
        }
        double *xi = x + 3 * i, *vi = v + 3 * i, *ni = n + 3 * i, *ai = arm + 3 * i;
        for (int j = 0; j < 3; ++j) { xi[j] = c[j] + a[j]; ni[j] = b[j]; ai[j] = a[j]; }
        vi[0] = V[0] + (w[1] * a[2] - w[2] * a[1]);
        vi[1] = V[1] + (w[2] * a[0] - w[0] * a[2]);
        vi[2] = V[2] + (w[0] * a[1] - w[1] * a[0]);
    }
}

/* k points; arm, f (k, 3). Out: FM (6) = sum f, sum arm x f. */
void force_moment(int32_t k, const double *arm, const double *f, double *FM) {
    double s[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (int32_t i = 0; i < k; ++i) {
        const double *a = arm + 3 * i, *g = f + 3 * i;
        s[0] += g[0]; s[1] += g[1]; s[2] += g[2];
        s[3] += a[1] * g[2] - a[2] * g[1];
        s[4] += a[2] * g[0] - a[0] * g[2];
        s[5] += a[0] * g[1] - a[1] * g[0];
    }
    for (int j = 0; j < 6; ++j) FM[j] = s[j];
}
