#include "bindings.h"
#include "convert.h"

namespace polrig::python {

void bind_nav(py::module_& m) {
  (void)m;
}

}  // namespace polrig::python
