/* The material law's interface (materials_kernel.c): the layout of a material's parameter vector and the kinds
 * (fepen/laws/materials.py reads them with fepen.native.c_enums), and the two functions Python calls (ctypes and
 * numba: their signatures are read from these prototypes). cell_kernel.c includes materials_kernel.c. */
#ifndef FEPEN_MATERIALS_KERNEL_H
#define FEPEN_MATERIALS_KERNEL_H

/* the layout of a material's parameter vector (fepen.laws.materials) */
enum { KIND, E_, NU, RHO, A_, B_, N_, C_, M_, TMELT, TROOM, EPS0, CP, BETA, RATE_ON, THERMAL_ON, H_, N_PARAMS };
enum { ELASTIC = 0, JOHNSON_COOK = 1, BILINEAR = 2 };

/* the return of a trial state q (Pa): out[0] the flow stress, out[1] the temperature after; returns d eps_p */
double material_radial_return(double q, double eps_p, double T, double dt, double G, const double *p, double *out);

/* the flow stress at plastic strain eps_p, plastic strain rate `rate` (1/s) and temperature T (K) */
double material_yield_stress(double eps_p, double rate, double T, const double *p);

#endif
