# Type stubs of the vff package (the extension vff._vff and vff._errors).
from typing import Any, Callable, Iterator, Literal, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
format_version: Tuple[int, int]

class Error(Exception):
    code: int
    name: str
    section: Optional[str]
    offset: Optional[int]
    message: str
    @property
    def validation_id(self) -> Optional[int]: ...

class IoError(Error, OSError): ...
class InvalidFileError(Error): ...
class MeshError(Error): ...
class SceneError(Error): ...
class InvalidArgumentError(Error, ValueError): ...
class UnsupportedError(Error): ...
class OperationError(Error, RuntimeError): ...
class GltfError(Error):
    """A glTF asset's field that may not be used: code is the rule's ID (14001 to 14103 of
    spec/gltf/VFF_visibility_field/README.md), name its name, path the JSON pointer of the place."""
    path: str

class Problem(NamedTuple):
    id: int
    name: str
    severity: str
    section: Optional[str]
    offset: Optional[int]
    message: str

Vec3 = Union[Sequence[float], npt.NDArray[np.float32]]
Bound = Union[None, float, npt.NDArray[np.float32]]

def batch_kernel() -> str: ...

class File:
    path: str
    version: Tuple[int, int]
    file_size: int
    center: Tuple[float, float, float]
    radius: float
    position_scheme: str
    position_param: int
    map_count: int
    direction_scheme: str
    map_resolution: int
    frame: str
    distance_encoding: str
    miss_code: int
    normal_encoding: str
    has_normals: bool
    layout: dict[str, Any]
    sections: list[dict[str, Any]]
    metadata: dict[str, Any]
    metadata_text: str
    # None, or a partial result's (map_begin, map_end), both None without a valid range (spec/partial.md)
    partial: Optional[Tuple[Optional[int], Optional[int]]]
    def describe(self) -> dict[str, Any]: ...
    def validate(self, decode_blocks: bool = True) -> list[Problem]: ...
    # map, distances, normals: index in [0, map_count - 1]; another integer (-1 too) raises IndexError
    # naming the range.
    def map(self, index: int, plane: str = "distance") -> np.ndarray: ...
    def maps(self, plane: str = "distance") -> np.ndarray: ...
    def distances(self, index: int) -> npt.NDArray[np.float32]: ...
    def normals(self, index: int) -> npt.NDArray[np.float32]: ...
    def slice(self, index: int, plane: str = "distance") -> npt.NDArray[np.uint8]: ...

def open(path: str, checksums: str = "all") -> File: ...
def inspect(path: str) -> dict[str, Any]: ...

class Hits:
    hit: npt.NDArray[np.bool_]
    t: npt.NDArray[np.float32]
    point: npt.NDArray[np.float32]
    normal: npt.NDArray[np.float32]
    inside: npt.NDArray[np.bool_]
    instance: Optional[npt.NDArray[np.int32]]  # a Scene's: the id of the instance hit, -1 for a miss
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[np.ndarray]: ...

# Where rays that start inside a bounding sphere start: on the object (spec/geometry.md 7.3) or
# elsewhere (7.4).
RayOrigin = Literal["on-object", "off-object"]

HitTuple = Tuple[bool, float, Tuple[float, float, float], Tuple[float, float, float], bool]

class _BatchQueries:
    # The batch queries of FieldQuery, Instance and Scene (a stub's base class only: at run time each
    # class defines its own).
    # Rays are checked as vff-query checks them, before any is answered: an origin or direction that
    # is not finite, a zero direction, a NaN tmin or tmax, or tmin > tmax raises ValueError naming the
    # first such ray ("ray 12: the direction is zero"); `out` is then left as it was. To answer the
    # good rays of a batch that has bad ones, select them first:
    #   ok = np.isfinite(o).all(1) & np.isfinite(d).all(1) & d.any(1)
    # threads: an integer >= 0 (0: all cores); a negative one raises ValueError.
    def intersect(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                  tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                  threads: int = 0, out: Optional[Hits] = None) -> Hits: ...
    def occluded(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                 tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                 threads: int = 0) -> npt.NDArray[np.bool_]: ...
    def visibility(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                   tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                   threads: int = 0) -> npt.NDArray[np.float32]: ...

class _Queries(_BatchQueries):
    def sites(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
              tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
              threads: int = 0) -> Tuple[npt.NDArray[np.int32], npt.NDArray[np.int32]]: ...
    # The one-ray calls refuse the same rays as the batches (ValueError "ray: the direction is zero").
    def intersect_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                      interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object") -> HitTuple: ...
    def occluded_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                     interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object") -> bool: ...
    def visibility_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                       interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object") -> float: ...

class FieldQuery(_Queries):
    def __init__(self, file: File) -> None: ...
    file: File
    payload_bytes: int
    has_normals: bool
    refined: bool
    refinement_bytes: int

class Instance(_Queries):
    def __init__(self, field: FieldQuery, rotation: Optional[npt.ArrayLike] = None, translation: Vec3 = (0, 0, 0),
                 scale: float = 1.0) -> None: ...
    @staticmethod
    def from_axis_angle(field: FieldQuery, axis: Vec3, radians: float, translation: Vec3 = (0, 0, 0),
                        scale: float = 1.0) -> "Instance": ...
    field: FieldQuery
    rotation: npt.NDArray[np.float32]
    translation: Tuple[float, float, float]
    scale: float
    world_sphere: Tuple[Tuple[float, float, float], float]

SceneHitTuple = Tuple[bool, float, Tuple[float, float, float], Tuple[float, float, float], bool, int]

class Scene:
    """Many instances answered together (vff/scene.h); answers equal the loop over the instances in
    id order. Queries need a commit() after add() or set_transform(); before, vff.OperationError."""
    def __init__(self) -> None: ...
    def add(self, field: Union[FieldQuery, Instance], rotation: Optional[npt.ArrayLike] = None,
            translation: Vec3 = (0, 0, 0), scale: float = 1.0) -> int: ...
    def set_transform(self, id: int, rotation: Optional[npt.ArrayLike] = None, translation: Vec3 = (0, 0, 0),
                      scale: float = 1.0) -> None: ...
    def commit(self) -> None: ...
    committed: bool
    names: list[str]
    def instance(self, id: int) -> Instance: ...
    def __len__(self) -> int: ...
    # sources: per ray, the id of the instance it starts on, -1 for none (spec/geometry.md 7.3, 7.4).
    def intersect(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                  tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0,
                  ray_origin: RayOrigin = "on-object", sources: Optional[npt.NDArray[np.integer]] = None,
                  threads: int = 0, out: Optional[Hits] = None) -> Hits: ...
    def occluded(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                 tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0,
                 ray_origin: RayOrigin = "on-object", sources: Optional[npt.NDArray[np.integer]] = None,
                 threads: int = 0) -> npt.NDArray[np.bool_]: ...
    def visibility(self, origins: npt.NDArray[np.float32], directions: npt.NDArray[np.float32], tmin: Bound = None,
                   tmax: Bound = None, *, interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0,
                   ray_origin: RayOrigin = "on-object", sources: Optional[npt.NDArray[np.integer]] = None,
                   threads: int = 0) -> npt.NDArray[np.float32]: ...
    def intersect_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                      interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                      source: Optional[int] = None) -> SceneHitTuple: ...
    def occluded_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                     interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                     source: Optional[int] = None) -> bool: ...
    def visibility_ray(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ..., *,
                       interpolated: bool = False, refined: bool = False, intra_bias: float = -1.0, ray_origin: RayOrigin = "on-object",
                       source: Optional[int] = None) -> float: ...
    def candidates(self, origin: Vec3, direction: Vec3, tmin: float = 0.0, tmax: float = ...) -> list[int]: ...

def load_scene(path: str, checksums: str = "all") -> Scene: ...

# bake and bake_file take vff-bake's options with its ranges: map_size 1 to 4096, count >= 0 (0: the
# scheme's default), threads >= 0, zstd_level 1 to 22, max_texture_size and max_layers 1 to 65536,
# gutter 0 to 64; an integer outside its range raises ValueError naming the option and the range.
def bake(vertices: npt.ArrayLike, faces: npt.ArrayLike, out: Optional[str] = None, *,
         progress: Optional[Callable[[int, int], Any]] = None, **options: Any) -> File: ...
def bake_file(path: str, out: str, *, progress: Optional[Callable[[int, int], Any]] = None, **options: Any) -> File: ...
def compress(src: str, dst: str, level: int = 19, filter: str = "auto", maps_per_block: int = 0) -> File: ...
def decompress(src: str, dst: str) -> File: ...
def convert(src: str, dst: str, *, codec: str = "stored", zstd_level: int = 19, maps_per_block: int = 0,
            target: Optional[str] = None, max_texture_size: Optional[int] = None, max_layers: Optional[int] = None,
            gutter: Optional[int] = None) -> File: ...

class GltfField:
    """The field one mesh of a glTF asset carries (the extension VFF_visibility_field)."""
    mesh: int
    """The mesh's index."""
    name: str
    """The mesh's name ("" without one)."""
    path: str
    """The JSON pointer of the extension object ("/meshes/0/extensions/VFF_visibility_field")."""
    buffer_view: Optional[int]
    """The payload's bufferView, or None (a uri)."""
    uri: Optional[str]
    """The payload's uri as written, or None (a bufferView)."""
    geometry_hash: str
    """The geometryHash the extension declares: 16 lowercase hex digits."""
    min: Tuple[float, float, float]
    """The bounds' minimum the extension declares (mesh space)."""
    max: Tuple[float, float, float]
    """The bounds' maximum the extension declares (mesh space)."""
    mesh_geometry_hash: Optional[str]
    """The geometry hash of the mesh's triangles as the asset ships them; None when not computed."""
    match: Literal["exact", "close", "mismatch", "unchecked"]
    """How the field matches its mesh: the hash (exact), the bounds within tau (close: used), neither
    (mismatch: not used); unchecked when the field has an error or check_geometry was False."""
    tolerance: float
    """tau = 2R/255: how far a close match's bounds may lie from the declared ones."""
    bounds_difference: float
    """The largest of the six differences between the declared and the shipped bounds."""
    valid: bool
    """No error (rules 14004 to 14011) on the mesh."""
    usable: bool
    """Valid and matched exact or close: rays may be answered with it."""
    nodes: list[dict[str, Any]]
    """The nodes that use the mesh: {"node": int, "name": str, "answered": bool, "reason": str}; a
    node that is not a similarity, skinned or morphed is not answered (reason says why)."""
    bytes: bytes
    """The payload, a complete .vff file (b"" when the field has an error)."""
    def open(self, checksums: str = "all") -> File:
        """The payload as a vff.File in memory; raises vff.GltfError when the field is not usable."""
        ...

class GltfFields:
    """The fields of a glTF asset and the problems of the extension's rules (vff.read_gltf_fields)."""
    path: str
    """The asset's path as given."""
    mesh_count: int
    """Meshes in the asset."""
    fields: list[GltfField]
    """One per mesh carrying the extension, in mesh order."""
    problems: list[dict[str, Any]]
    """Every problem in check order: {"rule": int, "name": str, "severity": "error" | "warning" |
    "note", "path": JSON pointer ("" for the file), "message": str}."""
    has_error: bool
    """Some problem is an error."""

def read_gltf_fields(path: str, check_geometry: bool = True) -> GltfFields:
    """Reads the fields of a glTF asset (.gltf or .glb) and checks them against the rules of
    spec/gltf/VFF_visibility_field/README.md. Every rule, 14001 (not glTF 2.0) included, is a problem
    in the result, not an exception; a file that cannot be opened or read raises vff.IoError (an
    OSError). check_geometry: match each field against its mesh (else every match is "unchecked" and
    no field is usable)."""
    ...
