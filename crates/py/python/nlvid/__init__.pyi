"""Type stubs of nlvid (the extension module nlvid._nlvid, re-exported)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
F64 = npt.NDArray[np.float64]
Quantity = str  # a number with a unit, e.g. "5 um", "0.12 N/m", "52 s"

class NlvidError(Exception):
    """Any error reported by nlvid (message as the CLI prints it)."""

class StudyError(NlvidError):
    """An error in a study file."""
    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    key: Optional[str]

class InputError(NlvidError, ValueError):
    """A bad argument given from Python (NaN, mismatched lengths, missing unit, ...)."""

class Study:
    """A validated study file (nlvid check)."""
    @property
    def name(self) -> str: ...
    @property
    def sha256(self) -> str: ...
    @property
    def warnings(self) -> List[str]: ...
    def values(self) -> List[Dict[str, Any]]: ...
    def as_dict(self) -> Dict[str, Any]: ...
    def check_report(self) -> Dict[str, Any]: ...
    def table(self) -> str: ...

def load_study(path: PathLike, strict: bool = False) -> Study:
    """Load and validate a study file (nlvid check); raises StudyError."""

def parse_study(text: str, name: str = "<string>", strict: bool = False) -> Study:
    """Validate study text given as a string."""

def simulate(
    study: Union[PathLike, Study], profile_times: Optional[Sequence[Quantity]] = None
) -> Dict[str, Any]:
    """One forward run of the study's [forward] model (nlvid simulate / membrane):
    the cell FE model (afm-fe), the 3D capsule FE model (capsule-fe), the
    membrane, the analytic models; the GIL is released during the run.

    Keys: provenance, model, parameters, curve (time and channels as float64
    arrays + units), peak_force_N, final_force_N, min_force_N, final,
    solver (afm-fe), profiles (membrane). capsule-fe channels: force, contact_area,
    ellipse_area, pressure_area, lost_area, pressure, volume,
    plate_displacement, in_contact, lost_contact."""

class MetaModel:
    """A Kriging meta-model (nlvid surrogate predict / check)."""
    @staticmethod
    def load(path: PathLike, meta: Optional[PathLike] = None) -> "MetaModel": ...
    @property
    def path(self) -> str: ...
    @property
    def input_names(self) -> List[str]: ...
    @property
    def output_names(self) -> List[str]: ...
    @property
    def dim(self) -> int: ...
    @property
    def n_outputs(self) -> int: ...
    @property
    def times(self) -> Optional[F64]: ...
    @overload
    def predict(self, x: F64) -> F64: ...
    @overload
    def predict(self, x: F64, mse: bool) -> Union[F64, Tuple[F64, F64]]: ...
    def check(self, x: F64, y: F64) -> Dict[str, Any]: ...

def fit(
    study: Union[PathLike, Study],
    data: Union[PathLike, Dict[str, Any], Sequence[Union[PathLike, Dict[str, Any]]]],
    starts: Optional[int] = None,
    seed: Optional[int] = None,
) -> Dict[str, Any]:
    """Fit one NLV parameter set to one or several curves (nlvid fit).

    A curve is a data file path or a dict of float64 arrays in SI: time [s],
    displacement [m], force [N], optional indentation [m] and label."""

class ForceCurve:
    """One force curve of an instrument file (SI units)."""
    @property
    def source(self) -> str: ...
    @property
    def metadata(self) -> Dict[str, Any]: ...
    @property
    def segments(self) -> List[Dict[str, Any]]: ...
    def summary(self, samples: bool = False) -> Dict[str, Any]: ...
    def to_csv(self) -> str: ...
    @staticmethod
    def from_columns(
        data: Any, metadata: Optional[Mapping[str, Any]] = None, source: Optional[str] = None
    ) -> "ForceCurve":
        """A curve from an afmformats data object (``afmformats.load_data(p)[i]``)
        or a dict of afmformats-named columns in SI: force [N], height (measured)
        and/or height (piezo) [m], time [s], segment. ``metadata`` (default:
        ``data.metadata``) needs ``spring constant`` [N/m]. Segment kinds are
        inferred from the piezo height."""
    def __len__(self) -> int: ...

# A curve argument of hertz / lee_radok: an nlvid ForceCurve, an afmformats
# data object (AFMForceDistance, AFMStressRelaxation, AFMCreepCompliance) or
# a dict of afmformats-named columns; duck-typed, afmformats is not required.
CurveLike = Union[ForceCurve, Any]

def read_jpk(
    path: PathLike,
    spring_constant: Optional[Quantity] = None,
    sensitivity: Optional[Quantity] = None,
) -> List[ForceCurve]:
    """Read a JPK force curve, force map or QI file (nlvid inspect)."""

def hertz(
    curve: CurveLike, tip_radius: Quantity, poisson: float = 0.5, contact: str = "deviation"
) -> Dict[str, Any]:
    """Paraboloidal Hertz fit of the approach (nlvid inspect --fit hertz)."""

def lee_radok(
    curve: CurveLike, tip_radius: Quantity, terms: int = 2, contact: str = "deviation"
) -> Dict[str, Any]:
    """Lee-Radok Prony fit of extend + hold (nlvid inspect --fit lee-radok)."""

def fit_hertz(
    separation: F64, force: F64, tip_radius: Quantity, poisson: float = 0.5
) -> Dict[str, Any]:
    """Hertz fit of force [N] against tip-sample separation [m]."""

def fit_lee_radok(
    time: F64, indentation: F64, force: F64, tip_radius: Quantity, terms: int = 2
) -> Dict[str, Any]:
    """Lee-Radok Prony fit of a ramp-hold from contact."""

def read_results(path: PathLike) -> Dict[str, Any]:
    """A per-cell results table as a dict of columns (numpy arrays, SI)."""

def results_frame(path: PathLike) -> Any:
    """The results table as a pandas DataFrame (needs pandas)."""

def compare(
    results: PathLike,
    groups: Optional[Sequence[str]] = None,
    t_end: Optional[Quantity] = None,
    points: int = 53,
    times: Optional[Sequence[Quantity]] = None,
    method: str = "matlab",
    out_dir: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """Group G(t) mean +- sd and rank-sum p(t) between two groups (nlvid compare)."""

def run_cohort(
    study: PathLike, input: PathLike, out: Optional[PathLike] = None
) -> Dict[str, Any]:
    """Fit every cell of a cohort (nlvid cohort); resumable."""
