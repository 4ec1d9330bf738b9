#pragma once
// The name of how Eigen's Levenberg–Marquardt (unsupported/Eigen/LevenbergMarquardt) ended, and
// whether that is convergence (a tolerance met) rather than a limit or bad input: for the fits
// below calib/ that report it (compass/unit_installation, sky/berry_fit).
#include <unsupported/Eigen/LevenbergMarquardt>

namespace polrig {

inline const char* lm_status_name(Eigen::LevenbergMarquardtSpace::Status s, bool& converged) {
  using S = Eigen::LevenbergMarquardtSpace::Status;
  converged = false;
  switch (s) {
    case S::NotStarted: return "NotStarted";
    // The callers' loops stop at their iteration limit while Eigen still says Running.
    case S::Running: return "IterationLimit";
    case S::UserAsked: return "UserAsked";
    case S::ImproperInputParameters: return "ImproperInputParameters";
    case S::TooManyFunctionEvaluation: return "TooManyFunctionEvaluation";
    case S::RelativeReductionTooSmall: converged = true; return "RelativeReductionTooSmall";
    case S::RelativeErrorTooSmall: converged = true; return "RelativeErrorTooSmall";
    case S::RelativeErrorAndReductionTooSmall: converged = true; return "RelativeErrorAndReductionTooSmall";
    case S::CosinusTooSmall: converged = true; return "CosinusTooSmall";
    case S::FtolTooSmall: converged = true; return "FtolTooSmall";
    case S::XtolTooSmall: converged = true; return "XtolTooSmall";
    case S::GtolTooSmall: converged = true; return "GtolTooSmall";
  }
  return "?";
}

}  // namespace polrig
