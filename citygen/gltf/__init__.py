"""The city as glTF 2.0 (``.glb`` / ``.gltf``), written through trimesh.

:mod:`citygen.gltf.meshes` turns the geometry the USD writer consumes into triangle meshes (numpy only);
:mod:`citygen.gltf.writer` assembles them into a trimesh scene and writes it. Only the writer imports trimesh, and
the pipeline imports the writer only when a glTF is asked for, so USD runs never load it.
"""

#: Output suffixes written as glTF.
GLTF_SUFFIXES = (".glb", ".gltf")
