# Stubs of the extension clothbake._bake (python/src/bake.cpp): pipeline::bake for Python.
# Private: use clothbake.bake.
from collections.abc import Callable
from typing import Any

def bake(
    fabric: str,
    output: str,
    progress: Callable[[str, float], object] | None,
    resolution: int,
    threads: int,
    force: bool,
    max_memory: int,
) -> dict[str, Any]: ...
