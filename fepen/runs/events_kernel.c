/* The stop rules of a penetration, in one place (docs/theory.md §11): fepen.runs.events.StopRules.penetration
 * calls penetration_outcome through ctypes each step, and rigid_batch.c includes this file and calls
 * penetration_rule on every shot, so the single, the deformable and the batched runs stop by one text.
 *
 *   perforated   every load point is beyond the rear face: y_max < -thickness (thickness < 0: none)
 *   ricochet     every load point is back above the face (y_min > 0) and the centre moves away (v_y > 0)
 *   embedded     only when the run has no end time: the centre no longer advances along the axis (V.a <= 0),
 *                or 1/2 M |V|^2 <= stop_energy * KE0
 *
 * Nothing is decided before the body has entered (some load point below the face, y_min < 0); *entered keeps
 * that memory between calls. Built without contracting a * b + c (-ffp-contract=off): V.a is summed one
 * rounding at a time, left to right. Returns 0 (go on), 1 perforated, 2 ricochet, 3 embedded. */
#ifndef FEPEN_EVENTS_KERNEL
#define FEPEN_EVENTS_KERNEL
#include <stdint.h>

#include "events_kernel.h"

static inline double events_dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline int32_t penetration_rule(double y_min, double y_max, const double *v, const double *axis, double mass,
                                       double ke0, double thickness, int32_t until_stopped, double stop_energy,
                                       int32_t *entered) {
    *entered = *entered || y_min < 0.0;
    if (!*entered) return OUTCOME_NONE;
    if (thickness >= 0.0 && y_max < -thickness) return OUTCOME_PERFORATED;
    if (y_min > 0.0 && v[1] > 0.0) return OUTCOME_RICOCHET;
    if (until_stopped && (events_dot3(v, axis) <= 0.0 || 0.5 * mass * events_dot3(v, v) <= stop_energy * ke0))
        return OUTCOME_EMBEDDED;
    return OUTCOME_NONE;
}

/* penetration_rule for Python: entered is one int32 in and out */
int32_t penetration_outcome(double y_min, double y_max, const double *v, const double *axis, double mass, double ke0,
                            double thickness, int32_t until_stopped, double stop_energy, int32_t *entered) {
    return penetration_rule(y_min, y_max, v, axis, mass, ke0, thickness, until_stopped, stop_energy, entered);
}
#endif
