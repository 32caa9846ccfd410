"""vff: precomputed 4D visibility fields for numpy.

    import numpy as np, vff
    f = vff.open("bunny.vff")                      # memory-mapped; f.map_count, f.metadata, f.validate()
    q = vff.FieldQuery(f)
    hits = q.intersect(origins, directions)        # (N, 3) float32 each -> hits.hit, .t, .point, .normal
    ao = q.visibility(origins, directions, tmax=0.5, interpolated=True)
    bunny = vff.Instance.from_axis_angle(q, (0, 1, 0), 0.5, translation=(2, 0, 0), scale=1.5)
    scene = vff.Scene(); scene.add(bunny); scene.add(q, translation=(-2, 0, 0)); scene.commit()
    hits = scene.intersect(origins, directions)    # hits.instance: which instance, -1 for a miss
    room = vff.load_scene("room.vffscene.json")    # a scene description (vff-bake --split)
    field = vff.bake(vertices, faces, map_size=32, normals=True)
    asset = vff.read_gltf_fields("scene.glb")       # the fields a glTF asset's meshes carry
    box = asset.fields[0].open()                   # a vff.File (vff.GltfError if it may not be used)

Errors are vff.Error subclasses carrying the libvff code (the validation ID for file problems), the
section and the offset. The version is libvff's (vff.__version__).
"""

from collections import namedtuple as _namedtuple

from ._errors import (Error, IoError, InvalidFileError, MeshError, SceneError, InvalidArgumentError,
                      UnsupportedError, OperationError, GltfError)

Problem = _namedtuple("Problem", "id name severity section offset message")
Problem.__doc__ = """One problem File.validate() found: its validation ID (spec/validation.md) and
name, "error" or "warning", the section's FourCC (or None), the file offset (or None), a message."""

from ._vff import (__version__, format_version, batch_kernel, File, FieldQuery, Instance, Scene, Hits, open,
                   load_scene, inspect, bake, bake_file, compress, decompress, convert, read_gltf_fields, GltfFields,
                   GltfField)

__all__ = ["Error", "IoError", "InvalidFileError", "MeshError", "SceneError", "InvalidArgumentError",
           "UnsupportedError", "OperationError", "GltfError", "Problem", "File", "FieldQuery", "Instance", "Scene", "Hits",
           "open", "load_scene", "inspect", "bake", "bake_file", "compress", "decompress", "convert",
           "batch_kernel", "format_version", "__version__", "read_gltf_fields", "GltfFields", "GltfField"]
