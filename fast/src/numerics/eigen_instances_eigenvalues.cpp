// One group of the instantiations of Eigen's decompositions for fast/ (the
// list and the reason: numerics/eigen_instances.hpp). An explicit
// instantiation definition may follow the header's declaration in the same
// unit ([temp.explicit]).
#include "numerics/eigen_instances.hpp"

#define FDSID_EIGEN_INSTANCE(T) template class T;
FDSID_EIGEN_EIGENVALUES(FDSID_EIGEN_INSTANCE)
#undef FDSID_EIGEN_INSTANCE
