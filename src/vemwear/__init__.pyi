"""Type stub of the lazy top-level API (see ``__init__.py``): each name re-exported."""

from .config import ConfigError as ConfigError
from .config import apply_overrides as apply_overrides
from .config import load_config as load_config
from .config import parse_config as parse_config
from .contact import CallableCompliance as CallableCompliance
from .contact import LinearCompliance as LinearCompliance
from .contact import TableCompliance as TableCompliance
from .mesh import Mesh as Mesh
from .mesh import read_mesh as read_mesh
from .mesh import rectangle_squares as rectangle_squares
from .mesh import rectangle_triangles as rectangle_triangles
from .mesh import rectangle_voronoi as rectangle_voronoi
from .mesh import tag_rectangle as tag_rectangle
from .mesh import voronoi_mesh as voronoi_mesh
from .mesh import write_mesh as write_mesh
from .post.results import load_result as load_result
from .post.results import save_result as save_result
from .runner import run_config as run_config
from .simulate import Problem as Problem
from .simulate import Result as Result
from .simulate import SolverOptions as SolverOptions
from .simulate import TimeGrid as TimeGrid
from .simulate import simulate as simulate
from .vem import Material as Material

__version__: str
__all__: list[str]
