/* The material law of fepen's deformable fidelities, its one home (fepen/laws/materials.py builds the parameter
   vectors; docs/theory.md §4): the flow stress of Johnson-Cook (rate, adiabatic heating, thermal softening) and of
   the bilinear law, and the radial return by safeguarded Newton. The C passes of the step include this file
   (fepen/solver/cell_kernel.c); fepen.laws.materials calls material_radial_return and material_yield_stress
   through ctypes (the numba kernels and the uniaxial driver), so that every path has one law. Built without
   contracting a * b + c (fepen.native). Python's min/max order is kept so that NaN propagates the same way. */
#include <math.h>
#include <stdint.h>

#include "materials_kernel.h"


static double homologous_temperature(double T, const double *p)
{
    double ts = (T - p[TROOM]) / (p[TMELT] - p[TROOM]);
    if (0.0 > ts) ts = 0.0;
    if (1.0 < ts) ts = 1.0;
    return ts;
}

/* flow stress at plastic strain eps_p, plastic strain rate `rate`, temperature T */
static double yield_stress(double eps_p, double rate, double T, const double *p)
{
    int kind = (int)p[KIND];
    if (kind == BILINEAR) return p[A_] + p[H_] * eps_p;
    if (kind != JOHNSON_COOK) return INFINITY;
    double e = 0.0 > eps_p ? 0.0 : eps_p;
    double s = p[A_] + p[B_] * pow(e, p[N_]);
    if (p[RATE_ON] > 0.0 && rate > p[EPS0]) s *= 1.0 + p[C_] * log(rate / p[EPS0]);
    if (p[THERMAL_ON] > 0.0) s *= 1.0 - pow(homologous_temperature(T, p), p[M_]);
    return s;
}

/* sigma_y(eps_p + d, d/dt, T) into the return value, its slope in d into *ds, the adiabatic temperature
   T = T0 + beta s_heat d / (rho c_p) into *Tn (materials._yield_and_slope) */
static double yield_and_slope(double eps_p, double d, double dt, double T0, const double *p, double s_heat,
                              double *ds, double *Tn)
{
    if ((int)p[KIND] == BILINEAR) {
        *ds = p[H_];
        *Tn = T0;
        return p[A_] + p[H_] * (eps_p + d);
    }
    double e = eps_p + d, emin = 1e-12;
    double ee = emin > e ? emin : e;
    double en = pow(ee, p[N_]);
    double h0 = p[A_] + p[B_] * en;
    double dh0 = e > emin ? p[N_] * p[B_] * en / ee : 0.0;
    if (dh0 > 1e3 * p[E_]) dh0 = 1e3 * p[E_];  /* n < 1: infinite slope at eps_p = 0; capped for Newton */
    double r = 1.0, dr = 0.0;
    if (p[RATE_ON] > 0.0 && dt > 0.0) {
        double rate = d / dt;
        if (rate > p[EPS0]) {
            r = 1.0 + p[C_] * log(rate / p[EPS0]);
            dr = p[C_] / d;
        }
    }
    double g = h0 * r, dg = dh0 * r + h0 * dr;
    if (p[THERMAL_ON] <= 0.0) {
        *ds = dg;
        *Tn = T0;
        return g;
    }
    double k = p[BETA] / (p[RHO] * p[CP]);
    double T = T0 + k * s_heat * d;
    double ts = homologous_temperature(T, p);
    *Tn = T;
    if (ts <= 0.0) {
        *ds = dg;
        return g;
    }
    double tm = pow(ts, p[M_]);
    double s = g * (1.0 - tm), dss = dg * (1.0 - tm);
    if (ts < 1.0) dss -= g * p[M_] * tm / ts * k * s_heat / (p[TMELT] - p[TROOM]);
    *ds = dss;
    return s;
}

/* q_trial - 3 G d - sigma_y(eps_p + d, d/dt, T(d)) = 0 for d >= 0 by safeguarded Newton
   (materials.radial_return); returns d, the flow stress into *sy and the temperature after into *Tn */
static double radial_return(double q, double eps_p, double T, double dt, double G, const double *p,
                            double *sy, double *Tn)
{
    if ((int)p[KIND] == ELASTIC) {
        *sy = INFINITY;
        *Tn = T;
        return 0.0;
    }
    double ds, Tdummy;
    double s0 = yield_and_slope(eps_p, 0.0, dt, T, p, 0.0, &ds, &Tdummy);
    if (q <= s0) {
        *sy = s0;
        *Tn = T;
        return 0.0;
    }
    double lo = 0.0, hi = q / (3.0 * G);
    double d = (q - s0) / (3.0 * G);
    if (1e-14 > d) d = 1e-14;
    if (hi < d) d = hi;
    double s = s0, Tk = T, s_heat = s0;
    for (int it = 0; it < 100; it++) {
        s = yield_and_slope(eps_p, d, dt, T, p, s_heat, &ds, &Tk);
        double f = q - 3.0 * G * d - s;
        if (fabs(f) <= 1e-12 * q && fabs(s - s_heat) <= 1e-12 * q) break;
        s_heat = s;
        if (f > 0.0) lo = d;
        else hi = d;
        double dn = d + f / (3.0 * G + ds);
        if (!(lo < dn && dn < hi)) dn = 0.5 * (lo + hi);  /* Newton left the bracket: bisect */
        d = dn;
    }
    *sy = s;
    *Tn = Tk;
    return d;
}

/* The law for ctypes and numba: the return of a trial state q (Pa) into out[0] (flow stress) and out[1] (the
   temperature after); returns the plastic strain increment d */
double material_radial_return(double q, double eps_p, double T, double dt, double G, const double *p, double *out)
{
    double sy, Tn;
    double d = radial_return(q, eps_p, T, dt, G, p, &sy, &Tn);
    out[0] = sy;
    out[1] = Tn;
    return d;
}

/* The flow stress at plastic strain eps_p, plastic strain rate `rate` (1/s) and temperature T (K) */
double material_yield_stress(double eps_p, double rate, double T, const double *p)
{
    return yield_stress(eps_p, rate, T, p);
}
