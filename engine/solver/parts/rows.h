// The constraint rows of the step, one part per row kind, each written once over the number type (kernels/number.h)
// and used by every row builder (SolverFeatherstone's: the blocks' lanes, engine/solver/blocks/rows.cpp, and the
// islands of articulations, engine/solver/islands/rows.cpp; SolverSemiImplicit's bodies,
// engine/solver/semi_implicit/), which keep only how a Jacobian is laid out and how M^-1 J^T is solved. A part reads
// the settings it names (erp, linear_slop, ...) of whichever solver's settings table it is given. A part says
// whether its row is on, its kind (the projection of its impulse in a sweep, kernels/pgs.h), its target and bounds,
// its softness, the impulse it starts from and the one it keeps for the next step:
//   limit_row.h          a joint's range, a tendon's length (LimitRow)
//   friction_loss_row.h  a dof's dry friction (FrictionLossRow)
//   equality_rows.h      Connect, Weld, JointCoupling (EqualityRow, BodyEquality, JointCoupling)
//   contact_rows.h       a contact's normal, sliding, torsional and rolling rows (ContactRows, ContactInput)
//   soft_row.h           MuJoCo's soft row (solref, solimp) that a limit, dry friction or equality row may be
//   contact_softness.h   where a contact's softness is computed (MuJoCo's solref, solimp: contact_softness)
//   contact_material.h   what a contact takes from its two shapes (friction, restitution, solref, solimp)
//   row_jacobian.h       a row's Jacobian entries for a point riding on a link
//   warm_start.h         the share of its last impulse a row starts from, the impulse it keeps
#pragma once

#include "engine/solver/parts/contact_rows.h"
#include "engine/solver/parts/equality_rows.h"
#include "engine/solver/parts/friction_loss_row.h"
#include "engine/solver/parts/limit_row.h"
#include "engine/solver/parts/row_jacobian.h"
#include "engine/solver/parts/warm_start.h"
