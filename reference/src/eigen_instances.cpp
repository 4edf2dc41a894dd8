// The one instantiation of the decompositions eigen_instances.hpp declares.
#include "eigen_instances.hpp"

#define FDSID_REFERENCE_INSTANTIATE_CLASS(T) template class T;
#define FDSID_REFERENCE_INSTANTIATE_MEMBER(F) template F;
FDSID_REFERENCE_EIGEN_DECOMPOSITIONS(FDSID_REFERENCE_INSTANTIATE_CLASS, FDSID_REFERENCE_INSTANTIATE_MEMBER)
