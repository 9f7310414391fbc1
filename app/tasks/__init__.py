"""The tasks (mug on rack, bowl and bottle on shelf), their anchors, demos and the demo/template library."""
