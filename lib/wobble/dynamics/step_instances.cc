// The plain (double) steps of the 2D and 3D bodies, instantiated once for every unit that
// steps a body (step.h and step3.h declare them extern).
#include "wobble/dynamics/step.h"
#include "wobble/dynamics/step3.h"

namespace wobble {

template StepStatus Accelerations<double, NoExtraForce>(const BodyModel&, const WorldParams&, int,
                                                        const BodyState<double>&, VecQ<double>*, ForceBreakdown<double>*,
                                                        ContactSet, const NoExtraForce&);
template StepStatus StepBody<double, NoExtraForce>(const BodyModel&, const WorldParams&, int, Integrator, double,
                                                   BodyState<double>*, const NoExtraForce&);
template void UpdateContacts<double>(const BodyModel&, const Ground&, BodyState<double>*);
template StepStatus StepBody3<double, NoExtraForce>(const BodyModel3&, const WorldParams3&, Integrator, double,
                                                    BodyState3<double>*, const NoExtraForce&);
template void UpdateContacts3<double>(const BodyModel3&, const GroundPlane&, BodyState3<double>*);

}  // namespace wobble
