#pragma once
#include <Eigen/Core>  // allowed
