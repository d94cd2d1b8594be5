#include "idmpc/model/frame.hpp"

#include <stdexcept>

namespace idmpc {
namespace {

// orthonormality tolerance: the importer normalizes, so only rounding remains (as Model's)
constexpr double kUnitTolerance = 1e-9;

}  // namespace

void check_frame(const Model& model, const Frame& frame) {
  const std::string where = (frame.name.empty() ? std::string("frame") : frame.name) +
                            (model.name.empty() ? "" : " of model '" + model.name + "'");
  if (frame.link < -1 || frame.link >= model.n) {
    throw std::invalid_argument(where + ": link " + std::to_string(frame.link) +
                                " is not a link of the model: expected -1 (the base) to " +
                                std::to_string(model.n - 1));
  }
  const Mat3<double>& E = frame.placement.E;
  if (!E.allFinite() || !frame.placement.r.allFinite()) {
    throw std::invalid_argument(where + ": placement is not finite");
  }
  const double deviation = (E * E.transpose() - Mat3<double>::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kUnitTolerance || E.determinant() < 0) {
    throw std::invalid_argument(where +
                                ": placement rotation must be orthonormal with determinant +1, got |E·Eᵀ − 1| = " +
                                std::to_string(deviation) + ", det E = " + std::to_string(E.determinant()));
  }
}

}  // namespace idmpc
