/* The target's forces on surface points in one pass (fepen/laws/target.py, docs/theory.md §8): immersion,
 * tunnel stress, wake, separation, free surface, onset, energy crater, sliding friction. A transcription of
 * target.load_on_points before its linear-crater scaling; the numpy functions stay the reference, and
 * tests/unit/laws/test_target_kernel.py holds the two together. Built once per machine, called by ctypes. */
#include <math.h>
#include <stdint.h>

/* p[]: the TargetLaw as numbers, in this order */
enum { P_DENSITY, P_Y, P_E, P_T, P_LAM, P_SIGMA_S, P_B, P_THICKNESS /* < 0: none */, P_CRATER /* 2: energy */,
       P_K, P_D, P_SEPARATION, P_PHI_MIN, P_FREE_SURFACE, P_FRICTION, P_MU, P_MU_DYNAMIC, P_MU_DECAY,
       P_LOCK_DENSITY, P_CRUSH_STRAIN, P_C_OVER_A, P_GIVEN_SIGMA_S, P_ONSET,
       P_TOP /* the material's own faces in a block of layers */, P_LOWER /* < 0: none */,
       P_SURFACE_RANGE /* the free face's reach in plastic-zone widths */, P_COUNT };

#define SIN_TOL 1e-9

static double clip01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

static double cavity_stress(const double *p, double ca) {
    double lam = p[P_LAM], alpha = 6.0 / (3.0 + 2.0 * lam), L = log(ca);
    double g = lam == 0.0 ? alpha * L : expm1(alpha * lam * L) / lam;
    return p[P_Y] * ((2.0 / alpha) * g + 1.0);
}

/* k points; x, v, n (k, 3); area, radius, Rm, sphi0 (k); axis (3) or NULL; gauss: ng nodes then ng weights.
 * Out: f (k, 3) and sig (k) (zero outside), sums: force (3), loaded count, loaded area. Returns P_COUNT. */
int32_t point_forces(int32_t k, const double *x, const double *v, const double *n, const double *area,
                     const double *radius, const double *Rm, const double *sphi0, const double *axis,
                     const double *p, const double *gauss, int32_t ng, double *f, double *sig, double *sums) {
    const double thk = p[P_THICKNESS], sin_min = sin(p[P_PHI_MIN]), sin_onset = sin(p[P_ONSET]);
    const double ref = p[P_FREE_SURFACE] != 0.0 ? cavity_stress(p, p[P_C_OVER_A]) : 1.0;
    const double mu_s = p[P_MU], mu_d = p[P_MU_DYNAMIC], decay = p[P_MU_DECAY];
    for (int j = 0; j < 5; ++j) sums[j] = 0.0;
    for (int32_t i = 0; i < k; ++i) {
        const double *xi = x + 3 * i, *vi = v + 3 * i, *ni = n + 3 * i;
        double *fi = f + 3 * i;
        fi[0] = fi[1] = fi[2] = 0.0;
        sig[i] = 0.0;
        double ell = sqrt(area[i]), y = xi[1];
        double frac = clip01(0.5 - (y + p[P_TOP]) / ell);
        if (p[P_LOWER] >= 0.0) frac *= clip01(0.5 + (y + p[P_LOWER]) / ell);
        if (!(frac > 0.0)) continue;
        double vn = vi[0] * ni[0] + vi[1] * ni[1] + vi[2] * ni[2];
        double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        double sin_phi = speed > 0.0 ? vn / fmax(speed, 1e-300) : 0.0;
        int loaded = sin_phi > SIN_TOL;
        if (axis) loaded = loaded && (vi[0] * axis[0] + vi[1] * axis[1] + vi[2] * axis[2] > 0.0);
        if (p[P_SEPARATION] != 0.0) loaded = loaded && sin_phi > sin_min;
        if (!loaded || !(vn > 0.0)) continue;
        /* L_e: the shortest distance to the block's front face, or its rear face when it has one */
        double depth = fmax(-y, 0.0), Le = thk >= 0.0 ? fmin(depth, fmax(thk - depth, 0.0)) : depth;
        double s = p[P_SIGMA_S];
        if (p[P_FREE_SURFACE] != 0.0) {
            double ca = fmin(p[P_C_OVER_A], 1.0 + Le / (p[P_SURFACE_RANGE] * fmax(radius[i], 1e-12)));
            s = p[P_GIVEN_SIGMA_S] != 0.0 ? p[P_SIGMA_S] * cavity_stress(p, ca) / ref : cavity_stress(p, ca);
        }
        if (p[P_ONSET] > 0.0) s *= fmin(sin_phi / sin_onset, 1.0);
        double sg = (s + p[P_B] * p[P_DENSITY] * vn * vn) * frac;
        if (p[P_CRATER] == 2.0 && -y < p[P_K] * p[P_D]) {
            double rho = fmax(radius[i], 1e-12), l = (p[P_C_OVER_A] - 1.0) * rho, integral = 0.0;
            for (int32_t g = 0; g < ng; ++g) {
                double w = 0.5 * l * (gauss[g] + 1.0), q = rho / (rho + w);
                integral += 0.5 * l * gauss[ng + g] * (1.0 + w / Rm[i]) * (1.0 + w * sphi0[i] / rho) * q * q * q * q;
            }
            double e_kin = 0.5 * p[P_LOCK_DENSITY] * vn * vn * integral;
            double e_str = p[P_CRUSH_STRAIN] * p[P_Y] * (2.0 * rho * Le + Le * Le) / rho;
            if (e_kin - e_str >= 0.0) sg = 0.0;
        }
        sig[i] = sg;
        double pa = sg * area[i];
        fi[0] = -pa * ni[0];
        fi[1] = -pa * ni[1];
        fi[2] = -pa * ni[2];
        if (p[P_FRICTION] != 0.0 && mu_s > 0.0) {
            double vt[3] = {vi[0] - vn * ni[0], vi[1] - vn * ni[1], vi[2] - vn * ni[2]};
            double st = sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
            if (st > 1e-9) {
                double mu = (decay == 0.0 || mu_d == mu_s) ? mu_s : mu_d + (mu_s - mu_d) * exp(-decay * st);
                double c = mu * pa / st;
                fi[0] -= c * vt[0];
                fi[1] -= c * vt[1];
                fi[2] -= c * vt[2];
            }
        }
        if (sg > 0.0) {
            sums[3] += 1.0;
            sums[4] += area[i];
        }
    }
    for (int32_t i = 0; i < k; ++i) {
        sums[0] += f[3 * i];
        sums[1] += f[3 * i + 1];
        sums[2] += f[3 * i + 2];
    }
    return P_COUNT;
}
