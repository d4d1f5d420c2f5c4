"""Atlas layer: the paper's Algorithm 1, on the CPU and vectorised over objects.

`parameterize` culls, projects and clips each object's bounds (B_world → B_viewport), adds
the border, packs the regions into layers (`packing`: shelf packing) and gives every object
its transform T into its atlas region (B_atlas); `Records` holds the result (R). Imports the
scene layer only: no GL here.
"""

from .packing import Packing, pack_shelves
from .parameterize import default_atlas_max, parameterize
from .records import Records

__all__ = ["Packing", "Records", "default_atlas_max", "pack_shelves", "parameterize"]
