#include "bindings.h"
#include "convert.h"

namespace polrig::python {

void bind_calibration(py::module_& m) {
  (void)m;
}

}  // namespace polrig::python
