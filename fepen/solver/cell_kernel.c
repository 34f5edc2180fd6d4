/* The elastic trial pass of fepen's stress update, in C so that the compiler vectorises it across cells.

   The arithmetic of fepen.kinematics.stress_update (its reference, written for numba, which does not
   vectorise it), written with edge matrices so that no per-cell reference gradients are streamed from
   memory (the pass is memory-bound on large meshes): with E, U, R the current, step-increment (v dt) and
   reference edge matrices of a cell and a = E - U/2 the mid-step one,
       F = E R^-1,  L = D F_m^-1 = U a^-1,  cof F = cof(E) R^T / det R,
   the Hughes-Winget (Cayley) rotation of the deviatoric stress, s += 2 G dev sym L, P = (s + p I) cof F
   with p the average of the cell's four nodal pressures. Cells whose trial von Mises stress exceeds their
   static flow stress are listed; their radial return is done afterwards, in fepen.kinematics.plastic_pass.

   Layouts: the deviatoric stress s is component-major (k * n + e) so that the cell loop's loads and stores
   are contiguous; nodal arrays (x, v, X, nodal_p) are row-major and gathered through dofs; P is written
   row-major (n, 9), as dolfinx packs the coefficient, through a small block buffer. No fast-math: NaN and
   inf propagate, so inverted or broken cells are still detected. Built by fepen/ckernel.py. */
#include <stdint.h>

#define BLOCK 64

/* Elastic trial state of cells [0, n). s (6, n) in/out, P (n, 9) out; yielding receives the indices of the
   cells over their flow stress sy0; returns their number. inv_detR = 1 / det R per cell. */
int32_t trial_pass(int32_t n, const double *restrict x, const double *restrict v, const double *restrict X,
                   double dt, const int32_t *restrict dofs, const double *restrict inv_detR,
                   const int32_t *restrict mat, const double *restrict G_m, const double *restrict nodal_p,
                   int32_t nmat, double *restrict s, const double *restrict sy0, double *restrict P,
                   int32_t *restrict yielding)
{
    double PT[9 * BLOCK];  /* P of one block, component-major: stays in L1 until copied out */
    double excess[BLOCK];  /* q_trial^2 - sigma_y^2 */
    int32_t n_yield = 0;
    for (int32_t e0 = 0; e0 < n; e0 += BLOCK) {
        int32_t nb = n - e0 < BLOCK ? n - e0 : BLOCK;
#pragma omp simd
        for (int32_t k = 0; k < nb; k++) {
            int32_t e = e0 + k;
            int32_t live = mat[e] >= 0;  /* eroded cells (material -1): P and s stay 0, never yielding */
            int32_t m = live ? mat[e] : 0;
            int32_t n0 = dofs[4 * e + 0];
            int32_t n1 = dofs[4 * e + 1];
            int32_t n2 = dofs[4 * e + 2];
            int32_t n3 = dofs[4 * e + 3];
            double x0_0 = x[3 * n0], x0_1 = x[3 * n0 + 1], x0_2 = x[3 * n0 + 2];
            double v0_0 = v[3 * n0], v0_1 = v[3 * n0 + 1], v0_2 = v[3 * n0 + 2];
            double X0_0 = X[3 * n0], X0_1 = X[3 * n0 + 1], X0_2 = X[3 * n0 + 2];
            double x1_0 = x[3 * n1], x1_1 = x[3 * n1 + 1], x1_2 = x[3 * n1 + 2];
            double v1_0 = v[3 * n1], v1_1 = v[3 * n1 + 1], v1_2 = v[3 * n1 + 2];
            double X1_0 = X[3 * n1], X1_1 = X[3 * n1 + 1], X1_2 = X[3 * n1 + 2];
            double x2_0 = x[3 * n2], x2_1 = x[3 * n2 + 1], x2_2 = x[3 * n2 + 2];
            double v2_0 = v[3 * n2], v2_1 = v[3 * n2 + 1], v2_2 = v[3 * n2 + 2];
            double X2_0 = X[3 * n2], X2_1 = X[3 * n2 + 1], X2_2 = X[3 * n2 + 2];
            double x3_0 = x[3 * n3], x3_1 = x[3 * n3 + 1], x3_2 = x[3 * n3 + 2];
            double v3_0 = v[3 * n3], v3_1 = v[3 * n3 + 1], v3_2 = v[3 * n3 + 2];
            double X3_0 = X[3 * n3], X3_1 = X[3 * n3 + 1], X3_2 = X[3 * n3 + 2];
            double pm = 0.25 * (nodal_p[n0 * nmat + m] + nodal_p[n1 * nmat + m] + nodal_p[n2 * nmat + m]
                                + nodal_p[n3 * nmat + m]);
            /* edge matrices, column j = edge from node 0 to node j + 1: current (E), step increment (U),
               mid-step (a = E - U/2), reference (R) */
            double E00 = x1_0 - x0_0, U00 = (v1_0 - v0_0) * dt, R00 = X1_0 - X0_0;
            double E01 = x2_0 - x0_0, U01 = (v2_0 - v0_0) * dt, R01 = X2_0 - X0_0;
            double E02 = x3_0 - x0_0, U02 = (v3_0 - v0_0) * dt, R02 = X3_0 - X0_0;
            double E10 = x1_1 - x0_1, U10 = (v1_1 - v0_1) * dt, R10 = X1_1 - X0_1;
            double E11 = x2_1 - x0_1, U11 = (v2_1 - v0_1) * dt, R11 = X2_1 - X0_1;
            double E12 = x3_1 - x0_1, U12 = (v3_1 - v0_1) * dt, R12 = X3_1 - X0_1;
            double E20 = x1_2 - x0_2, U20 = (v1_2 - v0_2) * dt, R20 = X1_2 - X0_2;
            double E21 = x2_2 - x0_2, U21 = (v2_2 - v0_2) * dt, R21 = X2_2 - X0_2;
            double E22 = x3_2 - x0_2, U22 = (v3_2 - v0_2) * dt, R22 = X3_2 - X0_2;
            double a00 = E00 - 0.5 * U00, a01 = E01 - 0.5 * U01, a02 = E02 - 0.5 * U02;
            double a10 = E10 - 0.5 * U10, a11 = E11 - 0.5 * U11, a12 = E12 - 0.5 * U12;
            double a20 = E20 - 0.5 * U20, a21 = E21 - 0.5 * U21, a22 = E22 - 0.5 * U22;
            double c00 = a11 * a22 - a12 * a21, c01 = a12 * a20 - a10 * a22, c02 = a10 * a21 - a11 * a20;
            double c10 = a02 * a21 - a01 * a22, c11 = a00 * a22 - a02 * a20, c12 = a01 * a20 - a00 * a21;
            double c20 = a01 * a12 - a02 * a11, c21 = a02 * a10 - a00 * a12, c22 = a00 * a11 - a01 * a10;
            double idet = 1.0 / (a00 * c00 + a01 * c01 + a02 * c02);
            double L00 = (U00 * c00 + U01 * c01 + U02 * c02) * idet;
            double L01 = (U00 * c10 + U01 * c11 + U02 * c12) * idet;
            double L02 = (U00 * c20 + U01 * c21 + U02 * c22) * idet;
            double L10 = (U10 * c00 + U11 * c01 + U12 * c02) * idet;
            double L11 = (U10 * c10 + U11 * c11 + U12 * c12) * idet;
            double L12 = (U10 * c20 + U11 * c21 + U12 * c22) * idet;
            double L20 = (U20 * c00 + U21 * c01 + U22 * c02) * idet;
            double L21 = (U20 * c10 + U21 * c11 + U22 * c12) * idet;
            double L22 = (U20 * c20 + U21 * c21 + U22 * c22) * idet;
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
            /* cof F = cof(E) cof(R^-1) = cof(E) R^T / det R */
            double k00 = E11 * E22 - E12 * E21, k01 = E12 * E20 - E10 * E22, k02 = E10 * E21 - E11 * E20;
            double k10 = E02 * E21 - E01 * E22, k11 = E00 * E22 - E02 * E20, k12 = E01 * E20 - E00 * E21;
            double k20 = E01 * E12 - E02 * E11, k21 = E02 * E10 - E00 * E12, k22 = E00 * E11 - E01 * E10;
            double r = inv_detR[e];
            double C00 = (k00 * R00 + k01 * R01 + k02 * R02) * r;
            double C01 = (k00 * R10 + k01 * R11 + k02 * R12) * r;
            double C02 = (k00 * R20 + k01 * R21 + k02 * R22) * r;
            double C10 = (k10 * R00 + k11 * R01 + k12 * R02) * r;
            double C11 = (k10 * R10 + k11 * R11 + k12 * R12) * r;
            double C12 = (k10 * R20 + k11 * R21 + k12 * R22) * r;
            double C20 = (k20 * R00 + k21 * R01 + k22 * R02) * r;
            double C21 = (k20 * R10 + k21 * R11 + k22 * R12) * r;
            double C22 = (k20 * R20 + k21 * R21 + k22 * R22) * r;
            s0 = live ? s0 : 0.0; s1 = live ? s1 : 0.0; s2 = live ? s2 : 0.0;
            s3 = live ? s3 : 0.0; s4 = live ? s4 : 0.0; s5 = live ? s5 : 0.0;
            pm = live ? pm : 0.0;
            C00 = live ? C00 : 0.0; C01 = live ? C01 : 0.0; C02 = live ? C02 : 0.0;
            C10 = live ? C10 : 0.0; C11 = live ? C11 : 0.0; C12 = live ? C12 : 0.0;
            C20 = live ? C20 : 0.0; C21 = live ? C21 : 0.0; C22 = live ? C22 : 0.0;
            s[0 * n + e] = s0; s[1 * n + e] = s1; s[2 * n + e] = s2; s[3 * n + e] = s3; s[4 * n + e] = s4; s[5 * n + e] = s5;
            excess[k] = live ? 1.5 * (s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)) - sy0[e] * sy0[e] : -1.0;
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
        for (int32_t k = 0; k < nb; k++)
            if (excess[k] > 0.0)
                yielding[n_yield++] = e0 + k;
    }
    return n_yield;
}
