/* The elastic trial pass of fepen's stress update, in C so that the compiler vectorises it across cells.

   The same arithmetic as fepen.kinematics.stress_update (its reference, written for numba, which does not
   vectorise it): F and the step increment D from the nodes, L = D F_m^-1 at the mid-step configuration,
   the Hughes-Winget (Cayley) rotation of the deviatoric stress, s += 2 G dev sym L, P = (s + p I) cof F
   with p the average of the cell's four nodal pressures; excess = q_trial^2 - sigma_y^2 flags the cells
   that yield (the radial return is done afterwards, on those cells only, in fepen.kinematics).

   Layouts: per-cell arrays are structure-of-arrays, component-major (k * n + e), so that every load and
   store of the cell loop is contiguous; nodal arrays (x, v, nodal_p) are row-major and gathered through
   dofs. No fast-math: NaN and inf propagate, so inverted or broken cells are still detected.
   Compiled by fepen/ckernel.py; see there for the flags. */
#include <stdint.h>

#define BLOCK 64

/* Elastic trial state of cells [0, n): sT (6, n) in/out, P (n, 9) row-major out (the coefficient as dolfinx
   packs it, written block by block), excess (n) out. */
void trial_pass(int32_t n, const double *restrict x, const double *restrict v, double dt,
                const int32_t *restrict dofs, const double *restrict grad0, const int32_t *restrict mat,
                const double *restrict G_m, const double *restrict nodal_p, int32_t nmat,
                double *restrict s, const double *restrict sy0, double *restrict P, double *restrict excess)
{
    double PT[9 * BLOCK];  /* P of one block, component-major: stays in L1 until copied out */
    for (int32_t e0 = 0; e0 < n; e0 += BLOCK) {
        int32_t nb = n - e0 < BLOCK ? n - e0 : BLOCK;
#pragma omp simd
        for (int32_t k = 0; k < nb; k++) {
            int32_t e = e0 + k;
            double pm = 0.0;
            int32_t m = mat[e];
            /* the four nodes: reference gradients, positions, step increments v dt, nodal pressures */
            int32_t nd0 = dofs[4 * e + 0];
            double g0_0 = grad0[0 * n + e], g1_0 = grad0[1 * n + e], g2_0 = grad0[2 * n + e];
            double x0_0 = x[3 * nd0], x1_0 = x[3 * nd0 + 1], x2_0 = x[3 * nd0 + 2];
            double u0_0 = v[3 * nd0] * dt, u1_0 = v[3 * nd0 + 1] * dt, u2_0 = v[3 * nd0 + 2] * dt;
            pm += nodal_p[nd0 * nmat + m];
            int32_t nd1 = dofs[4 * e + 1];
            double g0_1 = grad0[3 * n + e], g1_1 = grad0[4 * n + e], g2_1 = grad0[5 * n + e];
            double x0_1 = x[3 * nd1], x1_1 = x[3 * nd1 + 1], x2_1 = x[3 * nd1 + 2];
            double u0_1 = v[3 * nd1] * dt, u1_1 = v[3 * nd1 + 1] * dt, u2_1 = v[3 * nd1 + 2] * dt;
            pm += nodal_p[nd1 * nmat + m];
            int32_t nd2 = dofs[4 * e + 2];
            double g0_2 = grad0[6 * n + e], g1_2 = grad0[7 * n + e], g2_2 = grad0[8 * n + e];
            double x0_2 = x[3 * nd2], x1_2 = x[3 * nd2 + 1], x2_2 = x[3 * nd2 + 2];
            double u0_2 = v[3 * nd2] * dt, u1_2 = v[3 * nd2 + 1] * dt, u2_2 = v[3 * nd2 + 2] * dt;
            pm += nodal_p[nd2 * nmat + m];
            int32_t nd3 = dofs[4 * e + 3];
            double g0_3 = grad0[9 * n + e], g1_3 = grad0[10 * n + e], g2_3 = grad0[11 * n + e];
            double x0_3 = x[3 * nd3], x1_3 = x[3 * nd3 + 1], x2_3 = x[3 * nd3 + 2];
            double u0_3 = v[3 * nd3] * dt, u1_3 = v[3 * nd3 + 1] * dt, u2_3 = v[3 * nd3 + 2] * dt;
            pm += nodal_p[nd3 * nmat + m];
            /* F = sum_a x_a (x) grad0_a and D = sum_a (v_a dt) (x) grad0_a */
            double F00 = x0_0 * g0_0 + x0_1 * g0_1 + x0_2 * g0_2 + x0_3 * g0_3;
            double D00 = u0_0 * g0_0 + u0_1 * g0_1 + u0_2 * g0_2 + u0_3 * g0_3;
            double F01 = x0_0 * g1_0 + x0_1 * g1_1 + x0_2 * g1_2 + x0_3 * g1_3;
            double D01 = u0_0 * g1_0 + u0_1 * g1_1 + u0_2 * g1_2 + u0_3 * g1_3;
            double F02 = x0_0 * g2_0 + x0_1 * g2_1 + x0_2 * g2_2 + x0_3 * g2_3;
            double D02 = u0_0 * g2_0 + u0_1 * g2_1 + u0_2 * g2_2 + u0_3 * g2_3;
            double F10 = x1_0 * g0_0 + x1_1 * g0_1 + x1_2 * g0_2 + x1_3 * g0_3;
            double D10 = u1_0 * g0_0 + u1_1 * g0_1 + u1_2 * g0_2 + u1_3 * g0_3;
            double F11 = x1_0 * g1_0 + x1_1 * g1_1 + x1_2 * g1_2 + x1_3 * g1_3;
            double D11 = u1_0 * g1_0 + u1_1 * g1_1 + u1_2 * g1_2 + u1_3 * g1_3;
            double F12 = x1_0 * g2_0 + x1_1 * g2_1 + x1_2 * g2_2 + x1_3 * g2_3;
            double D12 = u1_0 * g2_0 + u1_1 * g2_1 + u1_2 * g2_2 + u1_3 * g2_3;
            double F20 = x2_0 * g0_0 + x2_1 * g0_1 + x2_2 * g0_2 + x2_3 * g0_3;
            double D20 = u2_0 * g0_0 + u2_1 * g0_1 + u2_2 * g0_2 + u2_3 * g0_3;
            double F21 = x2_0 * g1_0 + x2_1 * g1_1 + x2_2 * g1_2 + x2_3 * g1_3;
            double D21 = u2_0 * g1_0 + u2_1 * g1_1 + u2_2 * g1_2 + u2_3 * g1_3;
            double F22 = x2_0 * g2_0 + x2_1 * g2_1 + x2_2 * g2_2 + x2_3 * g2_3;
            double D22 = u2_0 * g2_0 + u2_1 * g2_1 + u2_2 * g2_2 + u2_3 * g2_3;
            pm *= 0.25;
            double a00 = F00 - 0.5 * D00, a01 = F01 - 0.5 * D01, a02 = F02 - 0.5 * D02;
            double a10 = F10 - 0.5 * D10, a11 = F11 - 0.5 * D11, a12 = F12 - 0.5 * D12;
            double a20 = F20 - 0.5 * D20, a21 = F21 - 0.5 * D21, a22 = F22 - 0.5 * D22;
            double c00 = a11 * a22 - a12 * a21, c01 = a12 * a20 - a10 * a22, c02 = a10 * a21 - a11 * a20;
            double c10 = a02 * a21 - a01 * a22, c11 = a00 * a22 - a02 * a20, c12 = a01 * a20 - a00 * a21;
            double c20 = a01 * a12 - a02 * a11, c21 = a02 * a10 - a00 * a12, c22 = a00 * a11 - a01 * a10;
            double idet = 1.0 / (a00 * c00 + a01 * c01 + a02 * c02);
            double L00 = (D00 * c00 + D01 * c01 + D02 * c02) * idet;
            double L01 = (D00 * c10 + D01 * c11 + D02 * c12) * idet;
            double L02 = (D00 * c20 + D01 * c21 + D02 * c22) * idet;
            double L10 = (D10 * c00 + D11 * c01 + D12 * c02) * idet;
            double L11 = (D10 * c10 + D11 * c11 + D12 * c12) * idet;
            double L12 = (D10 * c20 + D11 * c21 + D12 * c22) * idet;
            double L20 = (D20 * c00 + D21 * c01 + D22 * c02) * idet;
            double L21 = (D20 * c10 + D21 * c11 + D22 * c12) * idet;
            double L22 = (D20 * c20 + D21 * c21 + D22 * c22) * idet;
            double w0 = 0.25 * (L21 - L12), w1 = 0.25 * (L02 - L20), w2 = 0.25 * (L10 - L01);
            double c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2);
            double Q00 = 1.0 - c * (w1 * w1 + w2 * w2), Q11 = 1.0 - c * (w0 * w0 + w2 * w2), Q22 = 1.0 - c * (w0 * w0 + w1 * w1);
            double Q01 = c * (-w2 + w0 * w1), Q10 = c * (w2 + w0 * w1), Q02 = c * (w1 + w0 * w2);
            double Q20 = c * (-w1 + w0 * w2), Q12 = c * (-w0 + w1 * w2), Q21 = c * (w0 + w1 * w2);
            double S00 = s[0 * n + e], S11 = s[1 * n + e], S22 = s[2 * n + e], S01 = s[3 * n + e], S12 = s[4 * n + e], S02 = s[5 * n + e];
            double T00 = Q00 * S00 + Q01 * S01 + Q02 * S02;
            double T01 = Q00 * S01 + Q01 * S11 + Q02 * S12;
            double T02 = Q00 * S02 + Q01 * S12 + Q02 * S22;
            double T10 = Q10 * S00 + Q11 * S01 + Q12 * S02;
            double T11 = Q10 * S01 + Q11 * S11 + Q12 * S12;
            double T12 = Q10 * S02 + Q11 * S12 + Q12 * S22;
            double T20 = Q20 * S00 + Q21 * S01 + Q22 * S02;
            double T21 = Q20 * S01 + Q21 * S11 + Q22 * S12;
            double T22 = Q20 * S02 + Q21 * S12 + Q22 * S22;
            double tr = (L00 + L11 + L22) / 3.0;
            double G2 = 2.0 * G_m[m];
            double s0 = T00 * Q00 + T01 * Q01 + T02 * Q02 + G2 * (L00 - tr);
            double s1 = T10 * Q10 + T11 * Q11 + T12 * Q12 + G2 * (L11 - tr);
            double s2 = T20 * Q20 + T21 * Q21 + T22 * Q22 + G2 * (L22 - tr);
            double s3 = T00 * Q10 + T01 * Q11 + T02 * Q12 + G2 * 0.5 * (L01 + L10);
            double s4 = T10 * Q20 + T11 * Q21 + T12 * Q22 + G2 * 0.5 * (L12 + L21);
            double s5 = T00 * Q20 + T01 * Q21 + T02 * Q22 + G2 * 0.5 * (L02 + L20);
            double C00 = F11 * F22 - F12 * F21, C01 = F12 * F20 - F10 * F22, C02 = F10 * F21 - F11 * F20;
            double C10 = F02 * F21 - F01 * F22, C11 = F00 * F22 - F02 * F20, C12 = F01 * F20 - F00 * F21;
            double C20 = F01 * F12 - F02 * F11, C21 = F02 * F10 - F00 * F12, C22 = F00 * F11 - F01 * F10;
            s[0 * n + e] = s0; s[1 * n + e] = s1; s[2 * n + e] = s2; s[3 * n + e] = s3; s[4 * n + e] = s4; s[5 * n + e] = s5;
            excess[e] = 1.5 * (s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)) - sy0[e] * sy0[e];
            double p00 = s0 + pm, p11 = s1 + pm, p22 = s2 + pm;
            PT[0 * BLOCK + k] = p00 * C00 + s3 * C10 + s5 * C20;
            PT[1 * BLOCK + k] = p00 * C01 + s3 * C11 + s5 * C21;
            PT[2 * BLOCK + k] = p00 * C02 + s3 * C12 + s5 * C22;
            PT[3 * BLOCK + k] = s3 * C00 + p11 * C10 + s4 * C20;
            PT[4 * BLOCK + k] = s3 * C01 + p11 * C11 + s4 * C21;
            PT[5 * BLOCK + k] = s3 * C02 + p11 * C12 + s4 * C22;
            PT[6 * BLOCK + k] = s5 * C00 + s4 * C10 + p22 * C20;
            PT[7 * BLOCK + k] = s5 * C01 + s4 * C11 + p22 * C21;
            PT[8 * BLOCK + k] = s5 * C02 + s4 * C12 + p22 * C22;
        }
        for (int32_t i = 0; i < 9; i++)
            for (int32_t k = 0; k < nb; k++)
                P[9 * (e0 + k) + i] = PT[i * BLOCK + k];
    }
}
