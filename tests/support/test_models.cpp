#include "support/test_models.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>

#ifndef IDMPC_SOURCE_DIR
#error "IDMPC_SOURCE_DIR must be defined (the project's source directory)"
#endif

namespace idmpc::test {

std::vector<std::string> shipped_model_paths() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(IDMPC_SOURCE_DIR) / "mjcf";
  if (!fs::is_directory(dir)) {
    throw std::runtime_error("model directory '" + dir.string() + "' does not exist");
  }
  std::vector<std::string> paths;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    // hidden files are a generator's temporaries
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && entry.path().extension() == ".xml" && name[0] != '.') {
      paths.push_back(entry.path().string());
    }
  }
  if (paths.empty()) {
    throw std::runtime_error("model directory '" + dir.string() + "' holds no *.xml file");
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

std::string arm2_mjcf(const std::string& element, const std::string& attribute, const std::string& extra) {
  auto at = [&](const std::string& name) { return name == element ? " " + attribute : std::string(); };
  return R"(<mujoco model="arm2">
  <option timestep="0.001"/>
  <default><geom contype="0" conaffinity="0"/></default>
  <worldbody>
    <body name="link0" pos="0 0 1")" + at("link0") + R"(>
      <joint name="joint0" type="hinge" axis="0 1 0")" + at("joint0") + R"(/>
      <geom name="geom0" type="box" pos="0 0 0.25" size="0.05 0.05 0.25")" + (element == "geom0" ? "" : R"( mass="1")") +
         at("geom0") + R"(/>
      <body name="link1" pos="0 0 0.5">)" + (element == "inertial1" ? "<inertial " + attribute + "/>" : "") + R"(
        <joint name="joint1" type="hinge" axis="0 1 0"/>
        <geom type="box" pos="0 0 0.25" size="0.05 0.05 0.25" mass="1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor0" joint="joint0" ctrllimited="true")" +
         (attribute.find("ctrlrange") == std::string::npos ? R"( ctrlrange="-20 20")" : "") + at("motor0") + R"(/>
    <motor name="motor1" joint="joint1" ctrllimited="true" ctrlrange="-20 20"/>
  </actuator>)" + extra + R"(
</mujoco>
)";
}

}  // namespace idmpc::test
