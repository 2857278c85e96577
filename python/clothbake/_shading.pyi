# Stubs of the extension clothbake._shading (python/src/shading.cpp): the C interface's engine.
# Private: use the clothbake package, whose wrappers check shapes and dtypes first.
from typing import Final

import numpy as np
from numpy.typing import NDArray

CHUNK_SIZE: Final[int]
C_API_VERSION: Final[int]

def chunk_seed(seed: int, chunk: int) -> int: ...
def result_name(result: int) -> str: ...

class Asset:
    @property
    def source(self) -> str: ...
    def info(self) -> tuple[int, float, bool]: ...

def pixel_footprints(
    uv: NDArray[np.float64],
    duv_dx: NDArray[np.float64],
    duv_dy: NDArray[np.float64],
    scale: float,
    max_side: float,
    out: NDArray[np.float64],
) -> None: ...
def uv_differentials(
    t: NDArray[np.float64],
    direction: NDArray[np.float64],
    ddx: NDArray[np.float64],
    ddy: NDArray[np.float64],
    normal: NDArray[np.float64],
    dpdu: NDArray[np.float64],
    dpdv: NDArray[np.float64],
    out_dx: NDArray[np.float64],
    out_dy: NDArray[np.float64],
) -> None: ...
def open_file(path: str, trusted: bool) -> Asset: ...
def open_memory(data: bytes, trusted: bool) -> Asset: ...

class Evaluator:
    def __init__(
        self,
        asset: Asset,
        method: int,
        tables: int,
        sheen: int,
        spp: int,
        direct_max_side: float,
    ) -> None: ...
    def estimate(
        self,
        footprints: NDArray[np.float64],
        wi: NDArray[np.float64],
        wo: NDArray[np.float64],
        lobes: int,
        seed: int,
        threads: int,
        out: NDArray[np.float64],
    ) -> None: ...
    def sample(
        self,
        footprints: NDArray[np.float64],
        wo: NDArray[np.float64],
        u: NDArray[np.float64],
        threads: int,
        out_wi: NDArray[np.float64],
        out_pdf: NDArray[np.float64],
        out_valid: NDArray[np.bool_],
        out_delta: NDArray[np.bool_],
    ) -> None: ...
    def pdf(
        self,
        footprints: NDArray[np.float64],
        wi: NDArray[np.float64],
        wo: NDArray[np.float64],
        threads: int,
        out: NDArray[np.float64],
    ) -> None: ...
