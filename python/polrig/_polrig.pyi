# Type stubs for polrig._polrig (the compiled module); python/tests/test_stubs.py checks that every
# public name of the module is declared here and that nothing here is missing from the module.
from typing import Any, Callable, Mapping, Sequence, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
Array = npt.NDArray[np.float64]
Progress = Union[None, bool, Callable[[str, float, float], Any]]

__version__: str
git_revision: str

# ---- errors (module.cpp)
class RigError(ValueError): ...
class DataError(ValueError): ...
class CalibrationError(RuntimeError): ...

# ---- rig (rig_bindings.cpp)
class Rig:
    def __init__(self) -> None: ...
    @staticmethod
    def load(path: str, *, set: Mapping[str, Any] | None = None) -> Rig: ...
    @staticmethod
    def from_yaml(text: str, *, set: Mapping[str, Any] | None = None, origin: str = "(yaml string)") -> Rig: ...
    @staticmethod
    def from_dict(values: Mapping[str, Any], *, set: Mapping[str, Any] | None = None) -> Rig: ...
    def to_yaml(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def keys(self) -> list[str]: ...
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def update(self, values: Mapping[str, Any]) -> None: ...
    def __contains__(self, key: str) -> bool: ...
    def copy(self) -> Rig: ...
    @property
    def origin(self) -> str: ...
    @property
    def overrides(self) -> list[str]: ...
    # ---- studies on a rig (study_bindings.cpp)

# ---- end of studies on a rig

def rig_keys() -> list[dict[str, Any]]: ...

# ---- studies (study_bindings.cpp)

# ---- end of studies


# ---- calibration (calibration_bindings.cpp)

# ---- end of calibration


# ---- sky, drift, spectral (sky_bindings.cpp)

# ---- end of sky


# ---- navigation (nav_bindings.cpp)

# ---- end of navigation
