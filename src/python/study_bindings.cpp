#include "bindings.h"
#include "convert.h"

namespace polrig::python {

void bind_studies(py::module_& m) {
  (void)m;
}

}  // namespace polrig::python
