"""Camera intrinsics/extrinsics: estimation and storage; see the cell issue."""
