/* The deformable step's C passes' interface (cell_kernel.c, whose head says what each pass does): the functions
 * fepen/solver/ckernel.py calls (their ctypes signatures are read from these prototypes). */
#ifndef FEPEN_CELL_KERNEL_H
#define FEPEN_CELL_KERNEL_H
#include <stdint.h>

/* kinematics_pass's out (4): the smallest J = V / V0 over live cells and its cell, the smallest h/c and its cell
 * (cells as doubles, -1 for none); fepen/solver/ckernel.py reads them */
enum { KIN_J_MIN, KIN_J_CELL, KIN_DT_MIN, KIN_DT_CELL, KIN_COUNT };
/* cell_pass's totals (4): plastic work, heat, 0, the largest plastic increment */
enum { TOT_PLASTIC, TOT_HEAT, TOT_RESERVED, TOT_D_MAX, TOT_COUNT };

/* nodes, before the forces: v, du, u, x; the old forces' work into w */
void update_begin(int32_t n_nodes, int32_t n_owned, double h, double dt, const double *restrict a,
                  double *restrict v, double *restrict u, const double *restrict X, double *restrict x,
                  double *restrict du, const double *restrict fint, const double *restrict fext, double *restrict w);

/* nodes, after the forces: a = (f_ext - f_int) / m; the new forces' work into w */
void update_end(int32_t n_owned, const double *restrict fint, const double *restrict fext,
                const double *restrict mass, const uint8_t *restrict fixed, const double *restrict du,
                double *restrict a, double *restrict w);

/* p_a = K ln(J_a) / J_a per node and material */
void nodal_pressure(int32_t n_rows, const double *restrict vol, const double *restrict vol0,
                    const double *restrict bulk, int32_t nmat, double *restrict p);

/* the nodal volumes per material, summed on the grid of the quantum q */
void scatter_volumes(int32_t n, const int32_t *restrict dofs, const int64_t *restrict mat,
                     const double *restrict cvol, double q, int32_t nmat, int32_t n_rows, double *restrict vol);

/* the nodal forces, summed on the grid of the quantum q */
void scatter_forces(int32_t n, const int32_t *restrict dofs, const double *restrict Fc, double q, int32_t n_rows,
                    double *restrict f);

/* cells: current volumes, h/c, the nodal volumes; out (4): smallest J, its cell, smallest h/c, its cell */
void kinematics_pass(int32_t n, const double *restrict x, const int32_t *restrict dofs,
                     const int64_t *restrict mat, const double *restrict orient, const double *restrict vol0,
                     const double *restrict speed, int32_t with_step, double *restrict cvol,
                     double *restrict cell_dt, double *restrict out, double vq, int32_t nmat, int32_t n_rows,
                     double *restrict vol);

/* cells: stress, return, forces; totals (4); returns the cells that yielded */
int32_t cell_pass(int32_t n, const double *restrict x, const double *restrict v, double dt,
                  const int32_t *restrict dofs, const int64_t *restrict mat, const double *restrict orient,
                  int32_t nmat, const double *restrict params, const double *restrict G_m,
                  const double *restrict nodal_p, double *restrict s, double *restrict eps_p,
                  double *restrict temp, double *restrict sy0, double *restrict Fc, double fq, int32_t n_rows,
                  double *restrict f, double *restrict totals);

/* the outer surface's load points */
void facet_kinematics(int32_t nf, const double *restrict x_all, const double *restrict v_all,
                      const int64_t *restrict tri, const double *restrict n_flat0, const double *restrict N0,
                      const double *restrict area0, const double *restrict flat0, double *restrict x,
                      double *restrict v, double *restrict area, double *restrict n);

#endif
