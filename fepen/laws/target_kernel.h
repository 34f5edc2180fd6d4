/* The target law's interface (target_kernel.c): the law's numbers as Python passes them (fepen/laws/target.py's
 * _LAW, checked against this enum, name by name, when the kernel is loaded) and the functions fepen.native binds
 * (their ctypes signatures are read from these prototypes). rigid_batch.c includes target_kernel.c, this with it. */
#ifndef FEPEN_TARGET_KERNEL_H
#define FEPEN_TARGET_KERNEL_H
#include <stdint.h>

/* p[]: the TargetLaw as numbers, in this order */
enum { P_DENSITY, P_Y, P_E, P_T, P_LAM, P_SIGMA_S, P_B, P_THICKNESS /* < 0: none */, P_CRATER /* 2: energy */,
       P_K, P_D, P_SEPARATION, P_PHI_MIN, P_FREE_SURFACE, P_FRICTION, P_MU, P_MU_DYNAMIC, P_MU_DECAY,
       P_LOCK_DENSITY, P_CRUSH_STRAIN, P_C_OVER_A, P_GIVEN_SIGMA_S,
       P_WALL_SHEAR2 /* 2G of the tunnel's wall (Pa): its elastic stiffness 2G/a under a sideways push */,
       P_TOP /* the material's own faces in a block of layers */, P_LOWER /* < 0: none */,
       P_SURFACE_RANGE /* the free face's reach in plastic-zone widths */,
       P_RELOAD /* the tunnel wall's reload strength: the fraction of sigma_s that re-expands its cracked wall */,
       P_FIELD_SIGMA /* the concrete's random field on sigma_s (§8.8): the standard deviation of its logarithm */,
       P_FIELD_MODES /* its number of modes N; 0: none. The modes follow P_COUNT: (kx, ky, kz, phase) each */,
       P_COUNT };

/* point_forces's sums (5): the force (3, N), the points loaded, their area (m^2) (fepen/laws/target.py reads them) */
enum { SUM_FORCE, SUM_LOADED = SUM_FORCE + 3, SUM_AREA, SUM_COUNT };

/* sigma_s at the cavity wall for c/a = ca (docs/theory.md §4.1) */
double cavity_wall_stress(double Y, double lam, double ca);

/* the law on k points (f, sig, sums out; T the tunnel or NULL); returns the numbers of p it read */
int32_t point_forces(int32_t k, const double *x, const double *v, const double *n, const double *area,
                     const double *radius, const double *Rm, const double *sphi0, const double *axis,
                     const double *p, const double *gauss, int32_t ng, double *f, double *sig, double *sums,
                     const double *body_xi, double *T);

/* the random field's strength factor at k points; returns the numbers of p it read */
int32_t strength_field(int32_t k, const double *x, const double *p, double *out);

/* the tunnel's sectors of k offsets, by the polynomial and by atan2 alone (the tests) */
void tunnel_sectors(int32_t k, const double *r, const double *t, int32_t S, int32_t *q, int32_t *q_exact);

/* where k points lie in the tunnel: tunnel_clear's and tunnel_locate's answers, the push and distance (the tests) */
void tunnel_probe(const double *T, int32_t k, const double *x, const double *xi, int32_t *clear, int32_t *located,
                  double *delta, double *rho);

#endif
