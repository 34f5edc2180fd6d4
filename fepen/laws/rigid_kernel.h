/* The rigid body's load-point kernel's interface (rigid_kernel.c): the functions Python calls (their ctypes
 * signatures are read from these prototypes; fepen/runs/rigid.py passes their addresses to rigid_batch.c). */
#ifndef FEPEN_RIGID_KERNEL_H
#define FEPEN_RIGID_KERNEL_H
#include <stdint.h>

/* k points: x = c + R r0, v = V + w x (R r0), n = R N0, arm = R r0 (k, 3 each) */
void rigid_points(int32_t k, const double *r0, const double *N0, const double *R, const double *c,
                  const double *V, const double *w, double *x, double *v, double *n, double *arm);

/* k points: FM (6) = sum f, sum arm x f */
void force_moment(int32_t k, const double *arm, const double *f, double *FM);

#endif
