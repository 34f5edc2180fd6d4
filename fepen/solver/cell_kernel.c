/* The deformable step of fepen's explicit solver in C: a few passes over the cells and nodes, vectorised
   across cells by the compiler, with no Python between their pieces (docs/theory.md §3.3).

   Passes of one step (fepen/solver/explicit.py calls them in this order):
     update_begin     nodes: v += (dt_prev + dt)/2 a, du = dt v, u += du, x = X + u; the work of the old forces
     kinematics_pass  cells: current volume cvol and the nodal volumes per material summed from it, the
                      smallest J (inverted or NaN cells), and every STEP_EVERY steps h/c per cell
     nodal_pressure   nodes: p_a = K ln(J_a) / J_a per material
     cell_pass        cells, ONE fused pass: elastic trial stress (Hughes-Winget), the radial return of the
                      cells over their flow stress (inline, in the same block), and the cell's internal force
                      on its four nodes summed into f_int block by block (terms on a grid: exact sums, any
                      order; the kinematics pass sums the nodal volumes so too)
     scatter_*        cells -> nodes apart (the tests' and the numba path's)
     update_end       nodes: a = (f_ext - f_int) / m, the work of the new forces

   The arithmetic is that of the numba reference, fepen.solver.kernels.stress_update (the return: the one
   material law, fepen/laws/materials_kernel.c, which both call), written with edge matrices: with E, U the current
   and step-increment (v dt) edge matrices of a cell (column j = edge from node 0 to node j + 1) and
   a = E - U/2 the mid-step one,
       L = U a^-1,   f_j = (orient / 6) sigma cof(E) e_{j-1} (j = 1..3),   f_0 = -(f_1 + f_2 + f_3),
   which is V0 P grad0_j with P = J sigma F^-T: the reference geometry drops out of the force (sigma = s + p I,
   p the average of the cell's four nodal pressures of its material).

   Layouts: cell state is structure-of-arrays so that the cell loop streams it: the deviatoric stress s is
   component-major (6, n) (k * n + e), eps_p, temp, sy0, orient, vol0, cvol, cell_dt are (n,); dofs (n, 4)
   int32; mat (n,) int64 (-1: eroded); nodal arrays (x, v, u, X, a, f, nodal_p) are row-major (n_nodes, 3) or
   (n_nodes, n_materials) and gathered through dofs; Fc is (n, 4, 3) row-major, written through a small block
   buffer that stays in L1. Material parameters are the rows of fepen.laws.materials' parameter vectors.

   No fast-math: NaN and inf propagate (built with -fno-math-errno only, so that sqrt is one instruction and
   the loops that take it vectorise), so inverted or broken cells are still detected. Built and loaded by
   fepen/solver/ckernel.py (fepen/native.py). */
#include <math.h>
#include <stdint.h>

#define BLOCK 64

/* The material law (the layout of a material's parameter vector, the flow stress and the radial return):
   fepen/laws/materials_kernel.c, its one home, built here as it is built there (no contraction) */
#include "../laws/materials_kernel.c"

#include "cell_kernel.h"

/* ------------------------------------------------------------------------------------------------------
   Node passes */

/* Before the forces: v += h a (h = (dt_prev + dt) / 2), du = dt v, u += du, x = X + u over all n_nodes
   nodes (ghosts included); w (n, 2) gets each owned node's half of the old forces' work over the step,
   du . f_int / 2 and du . f_ext / 2 (the trapezoidal rule; each node's running sum is the same on any
   partition, and the solver sums the nodes exactly). */
void update_begin(int32_t n_nodes, int32_t n_owned, double h, double dt, const double *restrict a,
                  double *restrict v, double *restrict u, const double *restrict X, double *restrict x,
                  double *restrict du, const double *restrict fint, const double *restrict fext, double *restrict w)
{
    for (int32_t i = 0; i < 3 * n_nodes; i++) {
        double vi = v[i] + h * a[i];
        double di = dt * vi;
        double ui = u[i] + di;
        v[i] = vi;
        du[i] = di;
        u[i] = ui;
        x[i] = X[i] + ui;
    }
    for (int32_t n = 0; n < n_owned; n++) {  /* each node's own running sums: the same on any partition */
        const double *d = du + 3 * n, *fi = fint + 3 * n, *fe = fext + 3 * n;
        w[2 * n] += 0.5 * (d[0] * fi[0] + d[1] * fi[1] + d[2] * fi[2]);
        w[2 * n + 1] += 0.5 * (d[0] * fe[0] + d[1] * fe[1] + d[2] * fe[2]);
    }
}

/* After the forces: a = (f_ext - f_int) / m over the owned nodes (0 where fixed[i] != 0, fixed may be NULL);
   w (n, 2) gets each owned node's half of the new forces' work, du . f_int / 2 and du . f_ext / 2. */
void update_end(int32_t n_owned, const double *restrict fint, const double *restrict fext,
                const double *restrict mass, const uint8_t *restrict fixed, const double *restrict du,
                double *restrict a, double *restrict w)
{
    for (int32_t n = 0; n < n_owned; n++) {
        double im = 1.0 / mass[n];
        for (int32_t k = 0; k < 3; k++) {
            int32_t i = 3 * n + k;
            a[i] = (fext[i] - fint[i]) * im;
        }
        const double *d = du + 3 * n, *fi = fint + 3 * n, *fe = fext + 3 * n;
        w[2 * n] += 0.5 * (d[0] * fi[0] + d[1] * fi[1] + d[2] * fi[2]);
        w[2 * n + 1] += 0.5 * (d[0] * fe[0] + d[1] * fe[1] + d[2] * fe[2]);
    }
    if (fixed)
        for (int32_t i = 0; i < 3 * n_owned; i++)
            if (fixed[i]) a[i] = 0.0;
}

/* p_a = K ln(J_a) / J_a per node and material, J_a = V_a / V0_a; 0 where V0_a = 0 */
void nodal_pressure(int32_t n_rows, const double *restrict vol, const double *restrict vol0,
                    const double *restrict bulk, int32_t nmat, double *restrict p)
{
    for (int32_t n = 0; n < n_rows; n++)
        for (int32_t m = 0; m < nmat; m++) {
            int32_t i = n * nmat + m;
            double v0 = vol0[i];
            double Ja = vol[i] / v0;
            p[i] = v0 > 0.0 ? bulk[m] * log(Ja) / Ja : 0.0;
        }
}

/* ------------------------------------------------------------------------------------------------------
   Cell -> node sums (plain, in cell order; the solver may replace them by a canonical-order gather) */

/* vol (n_rows, nmat) = 0, then vol[dofs[e, j], mat[e]] += cvol[e] / 4 over the live cells, each term rounded
   to a multiple of the quantum q (a power of two): the sums of such terms are exact while below 2^53 q, so
   they do not depend on the order of the cells nor on the partition (docs/theory.md §3.4) */
void scatter_volumes(int32_t n, const int32_t *restrict dofs, const int64_t *restrict mat,
                     const double *restrict cvol, double q, int32_t nmat, int32_t n_rows, double *restrict vol)
{
    double iq = 1.0 / q;
    for (int32_t i = 0; i < n_rows * nmat; i++) vol[i] = 0.0;
    for (int32_t e = 0; e < n; e++) {
        int64_t m = mat[e];
        if (m < 0) continue;
        double c = nearbyint(0.25 * cvol[e] * iq) * q;
        for (int32_t j = 0; j < 4; j++) vol[dofs[4 * e + j] * nmat + m] += c;
    }
}

/* f (n_rows, 3) = 0, then f[dofs[e, j]] += Fc[e, j] rounded to a multiple of the quantum q (a power of two):
   exact sums, the same in any order and on any partition (see scatter_volumes) */
void scatter_forces(int32_t n, const int32_t *restrict dofs, const double *restrict Fc, double q, int32_t n_rows,
                    double *restrict f)
{
    double iq = 1.0 / q;
    for (int32_t i = 0; i < 3 * n_rows; i++) f[i] = 0.0;
    for (int32_t e = 0; e < n; e++)
        for (int32_t j = 0; j < 4; j++) {
            double *fn = f + 3 * dofs[4 * e + j];
            const double *c = Fc + 12 * e + 3 * j;
            fn[0] += nearbyint(c[0] * iq) * q;
            fn[1] += nearbyint(c[1] * iq) * q;
            fn[2] += nearbyint(c[2] * iq) * q;
        }
}

/* ------------------------------------------------------------------------------------------------------
   Cell passes */

/* kinematics_pass on the block [e0, e0 + nb): J (inf for eroded cells) into Jb, h/c (inf where not
   computed) into tb; with_step a constant after inlining, so that each variant is one vector loop */
static inline __attribute__((always_inline)) void
kinematics_block(int32_t e0, int32_t nb, const double *restrict x, const int32_t *restrict dofs,
                 const int64_t *restrict mat, const double *restrict orient, const double *restrict vol0,
                 const double *restrict speed, const int32_t with_step, double *restrict cvol,
                 double *restrict cell_dt, double *restrict Jb, double *restrict tb)
{
#pragma omp simd
    for (int32_t k = 0; k < nb; k++) {
        int32_t e = e0 + k;
        int32_t live = mat[e] >= 0;
        int32_t m = live ? (int32_t)mat[e] : 0;
        int32_t n0 = dofs[4 * e], n1 = dofs[4 * e + 1], n2 = dofs[4 * e + 2], n3 = dofs[4 * e + 3];
        double x0 = x[3 * n0], y0 = x[3 * n0 + 1], z0 = x[3 * n0 + 2];
        double x1 = x[3 * n1], y1 = x[3 * n1 + 1], z1 = x[3 * n1 + 2];
        double x2 = x[3 * n2], y2 = x[3 * n2 + 1], z2 = x[3 * n2 + 2];
        double x3 = x[3 * n3], y3 = x[3 * n3 + 1], z3 = x[3 * n3 + 2];
        double ax = x1 - x0, ay = y1 - y0, az = z1 - z0;
        double bx = x2 - x0, by = y2 - y0, bz = z2 - z0;
        double cx = x3 - x0, cy = y3 - y0, cz = z3 - z0;
        double six = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
        double J = six / (6.0 * vol0[e]) * orient[e];
        double V = J * vol0[e];
        cvol[e] = live ? V : 0.0;
        Jb[k] = live ? J : INFINITY;
        if (with_step) {
            /* shortest altitude = 3 V / largest face area; faces (1,2,3), (2,3,0), (3,0,1), (0,1,2) */
            double dx = x3 - x1, dy = y3 - y1, dz = z3 - z1;
            double ex = x2 - x1, ey = y2 - y1, ez = z2 - z1;
            double f0x = ey * dz - ez * dy, f0y = ez * dx - ex * dz, f0z = ex * dy - ey * dx;
            double f1x = by * cz - bz * cy, f1y = bz * cx - bx * cz, f1z = bx * cy - by * cx;
            double f2x = ay * cz - az * cy, f2y = az * cx - ax * cz, f2z = ax * cy - ay * cx;
            double f3x = ay * bz - az * by, f3y = az * bx - ax * bz, f3z = ax * by - ay * bx;
            double a0 = f0x * f0x + f0y * f0y + f0z * f0z, a1 = f1x * f1x + f1y * f1y + f1z * f1z;
            double a2 = f2x * f2x + f2y * f2y + f2z * f2z, a3 = f3x * f3x + f3y * f3y + f3z * f3z;
            double amax = 0.0;
            amax = a0 > amax ? a0 : amax;
            amax = a1 > amax ? a1 : amax;
            amax = a2 > amax ? a2 : amax;
            amax = a3 > amax ? a3 : amax;
            int32_t ok = live & (amax > 0.0) & (V > 0.0);  /* & not &&: no branch */
            double t = 3.0 * V / (0.5 * sqrt(amax)) / speed[m];
            tb[k] = ok ? t : INFINITY;
            cell_dt[e] = ok ? t : cell_dt[e];
        } else {
            tb[k] = INFINITY;
        }
    }
}

/* Current volume of every cell into cvol (0 for eroded cells); with_step: each live cell's shortest altitude
   over its dilatational speed into cell_dt (left as it was where the volume or the faces vanish). vol (n_rows,
   nmat), unless NULL: the nodal volumes per material, zeroed and summed as scatter_volumes sums them (quantum
   vq), block by block while the block's cells are in cache.
   out: [smallest J = V / V0 over live cells (a NaN wins), its cell, smallest h/c (inf if not with_step), its
   cell] (cells as doubles, -1 for none): the first of equal minima, the first NaN. */
void kinematics_pass(int32_t n, const double *restrict x, const int32_t *restrict dofs,
                     const int64_t *restrict mat, const double *restrict orient, const double *restrict vol0,
                     const double *restrict speed, int32_t with_step, double *restrict cvol,
                     double *restrict cell_dt, double *restrict out, double vq, int32_t nmat, int32_t n_rows,
                     double *restrict vol)
{
    double Jb[BLOCK], tb[BLOCK];
    double jmin = INFINITY, dtmin = INFINITY;
    int32_t worst = -1, dtcell = -1;
    double ivq = vol ? 1.0 / vq : 0.0;
    if (vol)
        for (int32_t i = 0; i < n_rows * nmat; i++) vol[i] = 0.0;
    for (int32_t e0 = 0; e0 < n; e0 += BLOCK) {
        int32_t nb = n - e0 < BLOCK ? n - e0 : BLOCK;
        if (with_step)
            kinematics_block(e0, nb, x, dofs, mat, orient, vol0, speed, 1, cvol, cell_dt, Jb, tb);
        else
            kinematics_block(e0, nb, x, dofs, mat, orient, vol0, speed, 0, cvol, cell_dt, Jb, tb);
        for (int32_t k = 0; k < nb; k++) {
            double J = Jb[k];
            if (!(J >= jmin) && jmin == jmin && mat[e0 + k] >= 0) {  /* smaller, or the first NaN */
                jmin = J;
                worst = e0 + k;
            }
            if (tb[k] < dtmin) {
                dtmin = tb[k];
                dtcell = e0 + k;
            }
        }
        if (vol)  /* the block's nodal volumes while its cells are in cache: scatter_volumes' terms */
            for (int32_t e = e0; e < e0 + nb; e++) {
                int64_t m = mat[e];
                if (m < 0) continue;
                double c = nearbyint(0.25 * cvol[e] * ivq) * vq;
                for (int32_t j = 0; j < 4; j++) vol[dofs[4 * e + j] * nmat + m] += c;
            }
    }
    out[KIN_J_MIN] = jmin;
    out[KIN_J_CELL] = worst;
    out[KIN_DT_MIN] = dtmin;
    out[KIN_DT_CELL] = dtcell;
}

/* The fused stress and force pass over cells [0, n), one block of BLOCK cells at a time:
     1. (vectorised) the elastic trial deviatoric stress, its von Mises stress, cof(E), the current volume;
     2. (scalar, only the cells of the block over their static flow stress sy0) the radial return: s scaled
        to the flow stress, eps_p, temp, sy0 updated, plastic work, heat and the largest increment summed
        into totals (kernels.stress_update's bookkeeping);
     3. (vectorised) s stored, the cell's four nodal forces into Fc.
     4. f (n_rows, 3), unless NULL: zeroed, then each cell's four forces summed at its nodes as scatter_forces
        sums them (quantum fq), while the block is in cache: Fc need not be stored nor read back.
   s (6, n) in/out; Fc (n, 4, 3) out (zero for eroded cells), unless NULL; totals (4,) out: plastic work, heat, 0, the
   largest plastic increment. params (nmat, N_PARAMS); G_m shear modulus per material; nodal_p
   (n_nodes, nmat). Returns the number of cells that yielded. */
int32_t cell_pass(int32_t n, const double *restrict x, const double *restrict v, double dt,
                  const int32_t *restrict dofs, const int64_t *restrict mat, const double *restrict orient,
                  int32_t nmat, const double *restrict params, const double *restrict G_m,
                  const double *restrict nodal_p, double *restrict s, double *restrict eps_p,
                  double *restrict temp, double *restrict sy0, double *restrict Fc, double fq, int32_t n_rows,
                  double *restrict f, double *restrict totals)
{
    double sb[6][BLOCK], kb[9][BLOCK], pb[BLOCK], qb[BLOCK], vb[BLOCK], wb[BLOCK], Fb[12][BLOCK];
    int32_t yb[BLOCK];
    int32_t n_yield = 0;
    double plastic = 0.0, heat = 0.0, dmax = 0.0;
    double ifq = f ? 1.0 / fq : 0.0;
    if (f)
        for (int32_t i = 0; i < 3 * n_rows; i++) f[i] = 0.0;
    for (int32_t e0 = 0; e0 < n; e0 += BLOCK) {
        int32_t nb = n - e0 < BLOCK ? n - e0 : BLOCK;
        /* 1. trial state */
#pragma omp simd
        for (int32_t k = 0; k < nb; k++) {
            int32_t e = e0 + k;
            int32_t live = mat[e] >= 0;
            int32_t m = live ? (int32_t)mat[e] : 0;
            int32_t n0 = dofs[4 * e + 0], n1 = dofs[4 * e + 1], n2 = dofs[4 * e + 2], n3 = dofs[4 * e + 3];
            double x0_0 = x[3 * n0], x0_1 = x[3 * n0 + 1], x0_2 = x[3 * n0 + 2];
            double x1_0 = x[3 * n1], x1_1 = x[3 * n1 + 1], x1_2 = x[3 * n1 + 2];
            double x2_0 = x[3 * n2], x2_1 = x[3 * n2 + 1], x2_2 = x[3 * n2 + 2];
            double x3_0 = x[3 * n3], x3_1 = x[3 * n3 + 1], x3_2 = x[3 * n3 + 2];
            double v0_0 = v[3 * n0], v0_1 = v[3 * n0 + 1], v0_2 = v[3 * n0 + 2];
            double v1_0 = v[3 * n1], v1_1 = v[3 * n1 + 1], v1_2 = v[3 * n1 + 2];
            double v2_0 = v[3 * n2], v2_1 = v[3 * n2 + 1], v2_2 = v[3 * n2 + 2];
            double v3_0 = v[3 * n3], v3_1 = v[3 * n3 + 1], v3_2 = v[3 * n3 + 2];
            double pm = 0.25 * (nodal_p[n0 * nmat + m] + nodal_p[n1 * nmat + m] + nodal_p[n2 * nmat + m]
                                + nodal_p[n3 * nmat + m]);
            pb[k] = live ? pm : 0.0;
            /* edge matrices: current (E), step increment (U), mid-step (a = E - U/2) */
            double E00 = x1_0 - x0_0, U00 = (v1_0 - v0_0) * dt;
            double E01 = x2_0 - x0_0, U01 = (v2_0 - v0_0) * dt;
            double E02 = x3_0 - x0_0, U02 = (v3_0 - v0_0) * dt;
            double E10 = x1_1 - x0_1, U10 = (v1_1 - v0_1) * dt;
            double E11 = x2_1 - x0_1, U11 = (v2_1 - v0_1) * dt;
            double E12 = x3_1 - x0_1, U12 = (v3_1 - v0_1) * dt;
            double E20 = x1_2 - x0_2, U20 = (v1_2 - v0_2) * dt;
            double E21 = x2_2 - x0_2, U21 = (v2_2 - v0_2) * dt;
            double E22 = x3_2 - x0_2, U22 = (v3_2 - v0_2) * dt;
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
            /* Hughes-Winget rotation Q = (I - W/2)^-1 (I + W/2) in closed form (Cayley) */
            double w0 = 0.25 * (L21 - L12), w1 = 0.25 * (L02 - L20), w2 = 0.25 * (L10 - L01);
            double c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2);
            double Q00 = 1.0 - c * (w1 * w1 + w2 * w2), Q11 = 1.0 - c * (w0 * w0 + w2 * w2);
            double Q22 = 1.0 - c * (w0 * w0 + w1 * w1);
            double Q01 = c * (-w2 + w0 * w1), Q10 = c * (w2 + w0 * w1), Q02 = c * (w1 + w0 * w2);
            double Q20 = c * (-w1 + w0 * w2), Q12 = c * (-w0 + w1 * w2), Q21 = c * (w0 + w1 * w2);
            double S00 = s[0 * n + e], S11 = s[1 * n + e], S22 = s[2 * n + e];
            double S01 = s[3 * n + e], S12 = s[4 * n + e], S02 = s[5 * n + e];
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
            sb[0][k] = live ? s0 : 0.0; sb[1][k] = live ? s1 : 0.0; sb[2][k] = live ? s2 : 0.0;
            sb[3][k] = live ? s3 : 0.0; sb[4][k] = live ? s4 : 0.0; sb[5][k] = live ? s5 : 0.0;
            double q = sqrt(1.5 * (s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)));
            qb[k] = q;
            yb[k] = live & (q > sy0[e]);
            /* cof(E), columns: the area vectors of the faces opposite nodes 1, 2, 3 (times 2) */
            double k00 = E11 * E22 - E12 * E21, k01 = E12 * E20 - E10 * E22, k02 = E10 * E21 - E11 * E20;
            double k10 = E02 * E21 - E01 * E22, k11 = E00 * E22 - E02 * E20, k12 = E01 * E20 - E00 * E21;
            double k20 = E01 * E12 - E02 * E11, k21 = E02 * E10 - E00 * E12, k22 = E00 * E11 - E01 * E10;
            kb[0][k] = k00; kb[1][k] = k01; kb[2][k] = k02;
            kb[3][k] = k10; kb[4][k] = k11; kb[5][k] = k12;
            kb[6][k] = k20; kb[7][k] = k21; kb[8][k] = k22;
            wb[k] = orient[e] / 6.0;
            vb[k] = (E00 * k00 + E01 * k01 + E02 * k02) * orient[e] / 6.0;  /* current volume */
        }
        /* 2. radial return of the cells over their flow stress */
        for (int32_t k = 0; k < nb; k++) {
            if (!yb[k]) continue;
            int32_t e = e0 + k;
            int32_t m = (int32_t)mat[e];
            const double *p = params + (int64_t)m * N_PARAMS;
            if ((int)p[KIND] == ELASTIC) continue;
            double q = qb[k], sy, Tn;
            double d = radial_return(q, eps_p[e], temp[e], dt, G_m[m], p, &sy, &Tn);
            if (!(d > 0.0)) continue;
            double scale = sy / q;
            for (int32_t i = 0; i < 6; i++) sb[i][k] *= scale;
            eps_p[e] += d;
            temp[e] = Tn;
            sy0[e] = yield_stress(eps_p[e], 0.0, Tn, p);
            double V = vb[k];
            plastic += sy * d * V;
            if (p[THERMAL_ON] > 0.0) heat += p[BETA] * sy * d * V;
            if (d > dmax) dmax = d;
            n_yield++;
        }
        /* 3. the stress stored, the nodal forces f_j = (orient / 6) sigma cof(E) e_{j-1}, f_0 = -sum */
#pragma omp simd
        for (int32_t k = 0; k < nb; k++) {
            int32_t e = e0 + k;
            int32_t live = mat[e] >= 0;
            double s0 = sb[0][k], s1 = sb[1][k], s2 = sb[2][k], s3 = sb[3][k], s4 = sb[4][k], s5 = sb[5][k];
            s[0 * n + e] = s0; s[1 * n + e] = s1; s[2 * n + e] = s2;
            s[3 * n + e] = s3; s[4 * n + e] = s4; s[5 * n + e] = s5;
            double w = wb[k], pm = pb[k];
            double p00 = (s0 + pm) * w, p11 = (s1 + pm) * w, p22 = (s2 + pm) * w;
            double p01 = s3 * w, p12 = s4 * w, p02 = s5 * w;
            double k00 = kb[0][k], k01 = kb[1][k], k02 = kb[2][k];
            double k10 = kb[3][k], k11 = kb[4][k], k12 = kb[5][k];
            double k20 = kb[6][k], k21 = kb[7][k], k22 = kb[8][k];
            double f10 = p00 * k00 + p01 * k10 + p02 * k20;
            double f11 = p01 * k00 + p11 * k10 + p12 * k20;
            double f12 = p02 * k00 + p12 * k10 + p22 * k20;
            double f20 = p00 * k01 + p01 * k11 + p02 * k21;
            double f21 = p01 * k01 + p11 * k11 + p12 * k21;
            double f22 = p02 * k01 + p12 * k11 + p22 * k21;
            double f30 = p00 * k02 + p01 * k12 + p02 * k22;
            double f31 = p01 * k02 + p11 * k12 + p12 * k22;
            double f32 = p02 * k02 + p12 * k12 + p22 * k22;
            Fb[0][k] = live ? -(f10 + f20 + f30) : 0.0;
            Fb[1][k] = live ? -(f11 + f21 + f31) : 0.0;
            Fb[2][k] = live ? -(f12 + f22 + f32) : 0.0;
            Fb[3][k] = live ? f10 : 0.0; Fb[4][k] = live ? f11 : 0.0; Fb[5][k] = live ? f12 : 0.0;
            Fb[6][k] = live ? f20 : 0.0; Fb[7][k] = live ? f21 : 0.0; Fb[8][k] = live ? f22 : 0.0;
            Fb[9][k] = live ? f30 : 0.0; Fb[10][k] = live ? f31 : 0.0; Fb[11][k] = live ? f32 : 0.0;
        }
        if (Fc)
            for (int32_t k = 0; k < nb; k++)
                for (int32_t i = 0; i < 12; i++)
                    Fc[12 * (e0 + k) + i] = Fb[i][k];
        if (f) {  /* 4. the block's forces summed at the nodes as scatter_forces sums them (quantum fq) */
            for (int32_t k = 0; k < nb; k++) {
                const int32_t *d = dofs + 4 * (e0 + k);
                for (int32_t j = 0; j < 4; j++) {
                    double *fn = f + 3 * d[j];
                    fn[0] += nearbyint(Fb[3 * j][k] * ifq) * fq;
                    fn[1] += nearbyint(Fb[3 * j + 1][k] * ifq) * fq;
                    fn[2] += nearbyint(Fb[3 * j + 2][k] * ifq) * fq;
                }
            }
        }
    }
    totals[TOT_PLASTIC] = plastic;
    totals[TOT_HEAT] = heat;
    totals[TOT_RESERVED] = 0.0;
    totals[TOT_D_MAX] = dmax;
    return n_yield;
}

/* ------------------------------------------------------------------------------------------------------
   The outer surface's load points (fepen.solver.surface.Surface.kinematics; its numba _facet_kinematics is the
   reference: the same operations in the same order, so the same bits): each facet's centroid, mean velocity,
   stretched exact area, and the exact normal N0 turned by the smallest rotation taking the flat reference
   normal a to the current one b, R v = (a.b) v + (a x b) x v + ((a x b).v)(a x b) / max(1 + a.b, 1e-12) (that
   max as Python's: NaN kept). Vectorised across facets: its divisions are most of its time. */
void facet_kinematics(int32_t nf, const double *restrict x_all, const double *restrict v_all,
                      const int64_t *restrict tri, const double *restrict n_flat0, const double *restrict N0,
                      const double *restrict area0, const double *restrict flat0, double *restrict x,
                      double *restrict v, double *restrict area, double *restrict n)
{
#pragma omp simd
    for (int32_t i = 0; i < nf; i++) {
        int64_t i0 = tri[3 * i], i1 = tri[3 * i + 1], i2 = tri[3 * i + 2];
        double x00 = x_all[3 * i0], x01 = x_all[3 * i0 + 1], x02 = x_all[3 * i0 + 2];
        double x10 = x_all[3 * i1], x11 = x_all[3 * i1 + 1], x12 = x_all[3 * i1 + 2];
        double x20 = x_all[3 * i2], x21 = x_all[3 * i2 + 1], x22 = x_all[3 * i2 + 2];
        double ax = x10 - x00, ay = x11 - x01, az = x12 - x02;
        double bx = x20 - x00, by = x21 - x01, bz = x22 - x02;
        double cx = 0.5 * (ay * bz - az * by), cy = 0.5 * (az * bx - ax * bz), cz = 0.5 * (ax * by - ay * bx);
        double a = sqrt(cx * cx + cy * cy + cz * cz);
        double ux = cx / a, uy = cy / a, uz = cz / a; /* current unit normal of the flat facet */
        double px = n_flat0[3 * i], py = n_flat0[3 * i + 1], pz = n_flat0[3 * i + 2];
        double c = px * ux + py * uy + pz * uz;
        double kx = py * uz - pz * uy, ky = pz * ux - px * uz, kz = px * uy - py * ux;
        double vx = N0[3 * i], vy = N0[3 * i + 1], vz = N0[3 * i + 2];
        double one_c = 1.0 + c;
        double kv = (kx * vx + ky * vy + kz * vz) / (1e-12 > one_c ? 1e-12 : one_c);
        n[3 * i] = c * vx + (ky * vz - kz * vy) + kv * kx;
        n[3 * i + 1] = c * vy + (kz * vx - kx * vz) + kv * ky;
        n[3 * i + 2] = c * vz + (kx * vy - ky * vx) + kv * kz;
        area[i] = area0[i] * (a / flat0[i]);
        x[3 * i] = (x00 + x10 + x20) / 3.0;
        x[3 * i + 1] = (x01 + x11 + x21) / 3.0;
        x[3 * i + 2] = (x02 + x12 + x22) / 3.0;
        v[3 * i] = (v_all[3 * i0] + v_all[3 * i1] + v_all[3 * i2]) / 3.0;
        v[3 * i + 1] = (v_all[3 * i0 + 1] + v_all[3 * i1 + 1] + v_all[3 * i2 + 1]) / 3.0;
        v[3 * i + 2] = (v_all[3 * i0 + 2] + v_all[3 * i1 + 2] + v_all[3 * i2 + 2]) / 3.0;
    }
}

