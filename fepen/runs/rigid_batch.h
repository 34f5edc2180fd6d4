/* The rigid run's interface (rigid_batch.c: one step, or many shots): the per-shot numbers, the step's numbers and
 * the results as Python lays them out (fepen/runs/rigid.py's SHOT_NUMBERS and STEP, batch.py's RESULTS, checked
 * against these enums, name by name, when the kernel is loaded) and the functions fepen.native binds (their ctypes
 * signatures are read from these prototypes). */
#ifndef FEPEN_RIGID_BATCH_H
#define FEPEN_RIGID_BATCH_H
#include <stdint.h>

/* per-shot numbers, in this order (fepen/runs/rigid.py SHOT_NUMBERS) */
enum { S_MASS, S_DT, S_HARD_END, S_THICKNESS /* < 0: none */, S_UNTIL_STOPPED, S_HISTORY /* <= 0: none */,
       S_CRATER /* 1: the linear crater */, S_CRATER_KD, S_CRATER_C, S_KE0, S_STOP_ENERGY,
       S_TIP /* 3: the tip about the centre */, S_TAIL = S_TIP + 3, S_IINV = S_TAIL + 3 /* 9 */,
       S_TUNNEL = S_IINV + 9 /* 1: the tunnel (tunnel_kernel.c) */, S_SPACING, S_XI_SH, S_A0, S_RESERVED,
       S_SHOULDER /* 3: the shoulder's centre about the body's centre */, S_COUNT = S_SHOULDER + 3 };
/* per-shot results */
enum { R_T, R_STEPS, R_OUTCOME /* events_kernel.h's OUTCOME_ (0: ended) */, R_WORK, R_ENTERED,
       R_MAX_NOSE /* mm */, R_MAX_ERROR, R_ROWS, R_STATUS /* 0 ok, 1 a non-finite state */, R_COUNT };
/* one RK4 step's numbers (rigid_step): the force at its start (3, N), the work of the target's force and moment
 * over it (J), its angular impulse about O (3, N m s), the last stage's loaded points and their area (m^2) */
enum { STEP_FORCE, STEP_WORK = STEP_FORCE + 3, STEP_ANGULAR, STEP_LOADED = STEP_ANGULAR + 3, STEP_AREA, STEP_COUNT };
/* a shot's state y, as fepen.laws.rigid_body.RigidState.as_array lays it out: the centre (3), the unit quaternion
 * (4), the velocity (3), the angular momentum (3) */
enum { Y_CENTRE, Y_QUAT = Y_CENTRE + 3, Y_VELOCITY = Y_QUAT + 4, Y_MOMENTUM = Y_VELOCITY + 3,
       Y_COUNT = Y_MOMENTUM + 3 };

/* n shots sharing k load points (rigid_batch.c says what each argument holds); points, moment: rigid_kernel.h's
 * rigid_points and force_moment. Returns S_COUNT * 10000 + R_COUNT * 100 + nlaw, or -1 */
int32_t rigid_batch(int32_t n, int32_t k, const double *r0, const double *N0, const double *area, const double *ell,
                    const double *radius, const double *Rm, const double *sphi0, const double *gauss, int32_t ng,
                    void *points, void *moment, const double *sp, const double *laws, int32_t nlaw, double *y,
                    double *res, const double *xi, int32_t cap, int32_t sectors, double *tunnels);

/* one shot's one RK4 step, the batch's own (y advanced in place; T the tunnel or NULL; out STEP_COUNT; stages NULL
 * or 4 x 3 (k, 3)). Returns S_COUNT * 100 + STEP_COUNT, or -1 */
int32_t rigid_step(int32_t k, const double *r0, const double *N0, const double *area, const double *ell,
                   const double *radius, const double *Rm, const double *sphi0, const double *gauss, int32_t ng,
                   void *points, void *moment, const double *sp, const double *law, double *y, const double *xi,
                   double *T, double *out, double *stages);

/* an embedded stop's interpolation back to V.a = 0 (prev, y: Y_COUNT; y moved in place, lam the fraction of the
 * step kept). Returns 1 when it moved y */
int32_t rigid_stop_back(const double *prev, double *y, double *lam);

/* the batch's law on one set of points, for the tests against point_forces */
void batch_law(int32_t k, const double *x, const double *v, const double *n, const double *area, const double *ell,
               const double *radius, const double *Rm, const double *sphi0, const double *axis, const double *p,
               const double *gauss, int32_t ng, double *f, double *sums);

#endif
