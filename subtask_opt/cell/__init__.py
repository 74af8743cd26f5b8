"""The robot's cell: obstacles and tools (boxes, cylinders, spheres, STL/OBJ meshes), the
collision checks of configurations and legs, and the detours planned around obstacles."""
