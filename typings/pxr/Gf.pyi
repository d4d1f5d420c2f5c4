# see __init__.pyi: the module is made at import, its names are Any here
from typing import Any

def __getattr__(name: str) -> Any: ...
