/* The stop rules' interface (events_kernel.c): the outcome codes they return (fepen/runs/events.py's OUTCOMES,
 * checked against this enum, name by name, when the kernel is loaded) and the function Python calls (its ctypes
 * signature is read from this prototype). rigid_batch.c includes events_kernel.c. */
#ifndef FEPEN_EVENTS_KERNEL_H
#define FEPEN_EVENTS_KERNEL_H
#include <stdint.h>

/* penetration_rule's answers */
enum { OUTCOME_NONE /* go on */, OUTCOME_PERFORATED, OUTCOME_RICOCHET, OUTCOME_EMBEDDED, OUTCOME_COUNT };

/* penetration_rule for Python: entered is one int32 in and out */
int32_t penetration_outcome(double y_min, double y_max, const double *v, const double *axis, double mass, double ke0,
                            double thickness, int32_t until_stopped, double stop_energy, int32_t *entered);

#endif
