// Eigen's decompositions over the 50-digit scalar, compiled once
// (eigen_instances.cpp) and without the sanitizers and gcov in the CI's
// instrumented build, as fast/ does for double (fast/src/numerics/eigen_instances.hpp
// says how `extern template` works). Internal header of reference/.
//
// Only Eigen's template code moves: which decomposition each step calls, and
// every line of the reference, stay where they were. Measured with the CI's
// sanitizer + coverage flags (gcc 12): these instantiations alone take ~80 s of
// compile instrumented, ~35 s plain; the reference's one unit (fdsid_unity)
// compiled them instrumented before.
//
// LLT and PartialPivLU are not instantiated whole: their rcond() needs
// NumTraits<Real>::infinity(), which Boost 1.74 lacks (frf_id.cpp), so only the
// members that do the work are. A caller whose argument type differs from the
// one named here (an expression instead of a MatrixR) still compiles its own
// copy: slower to build, never wrong.
#pragma once

#include "fdsid/reference/spectrum_id.hpp"

#include <Eigen/Dense>

#define FDSID_REFERENCE_EIGEN_DECOMPOSITIONS(CLASS, MEMBER)                                                   \
  CLASS(Eigen::JacobiSVD<fdsid::reference::MatrixR>)                                                          \
  CLASS(Eigen::EigenSolver<fdsid::reference::MatrixR>)                                                        \
  MEMBER(Eigen::EigenSolver<fdsid::reference::MatrixR>& Eigen::EigenSolver<fdsid::reference::MatrixR>::      \
             compute<fdsid::reference::MatrixR>(const Eigen::EigenBase<fdsid::reference::MatrixR>&, bool))    \
  CLASS(Eigen::HouseholderQR<fdsid::reference::MatrixR>)                                                      \
  CLASS(Eigen::ColPivHouseholderQR<fdsid::reference::MatrixR>)                                                \
  MEMBER(Eigen::LLT<fdsid::reference::MatrixR>& Eigen::LLT<fdsid::reference::MatrixR>::compute<              \
         fdsid::reference::MatrixR>(const Eigen::EigenBase<fdsid::reference::MatrixR>&))                      \
  MEMBER(void Eigen::PartialPivLU<fdsid::reference::MatrixC>::compute())

#define FDSID_REFERENCE_EXTERN_CLASS(T) extern template class T;
#define FDSID_REFERENCE_EXTERN_MEMBER(F) extern template F;
FDSID_REFERENCE_EIGEN_DECOMPOSITIONS(FDSID_REFERENCE_EXTERN_CLASS, FDSID_REFERENCE_EXTERN_MEMBER)
#undef FDSID_REFERENCE_EXTERN_CLASS
#undef FDSID_REFERENCE_EXTERN_MEMBER
