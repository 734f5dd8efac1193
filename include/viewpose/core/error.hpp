#pragma once
// The one error type the library throws. Its message is a single line that names the file (when there
// is one) and what is wrong with it, ready to print as is: "scene.pcd: header says 307200 points but
// the data holds 1200".
#include <stdexcept>
#include <string>

namespace viewpose {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace viewpose
