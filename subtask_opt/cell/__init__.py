"""The robot's cell: obstacles and a tool (boxes and STL/OBJ meshes), the collision checks
of configurations and swept legs, and the detours planned around obstacles."""
