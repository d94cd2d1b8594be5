#include "app/data_dir_option.hpp"

#include <stdexcept>
#include <string>

#include "idmpc/experiment/data_dir.hpp"

namespace idmpc::app {

void add_data_dir_option(CLI::App& sub) {
  // runs while the command line is parsed, before the command's callback reads any shipped file
  sub.add_option_function<std::string>(
      "--data-dir",
      [](const std::string& dir) {
        if (dir.empty()) throw std::invalid_argument("--data-dir: expected a directory holding mjcf/, got ''");
        try {
          set_data_dir(dir);
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument(std::string("--data-dir: ") + e.what());
        }
      },
      std::string("directory holding idmpc's mjcf/ (models, task files, paper tables); default: $") +
          kDataDirVariable + ", else ../share/idmpc beside the executable");
}

}  // namespace idmpc::app
