"""The NIFT method as a library: clouds and meshes in, features and poses out (no simulator)."""
