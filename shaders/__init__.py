"""GLSL for the SDF gallery, kept as files, and the small moderngl renderer that compiles and runs them.

- ``sdf.glsl``: the distance functions, mirroring :mod:`kernels.sdf` name for name; the scene comes in as uniforms.
- ``shading.glsl``: Phong terms shared by both images.
- ``raymarch.frag``: sphere tracing, normals by central differences, soft shadows, ambient occlusion.
- ``mesh.vert`` / ``mesh.frag``: the marching-cubes mesh rasterised from the same camera.
- ``probe.frag``: the GLSL distance and colour at points from a float texture (how tests compare with numpy).
- :mod:`shaders.renderer`: :class:`~shaders.renderer.Renderer`, :func:`~shaders.renderer.render`, the camera.
"""
