"""Names the CLI's parser needs without loading the mesh libraries: object categories, pose settings."""

CATEGORIES: tuple[str, ...] = ("mug", "bowl", "bottle", "vase")
IN_DOMAIN: tuple[str, ...] = ("mug", "bowl", "bottle")  # vases stay out of training data
# upright: standing at a random yaw; arbitrary: a Haar-random rotation held in mid-air until grasped
# (the paper's teleported protocol); resting: dropped from a Haar-random rotation, settled on the table
POSES: tuple[str, ...] = ("upright", "arbitrary", "resting")
REVOLUTION: tuple[str, ...] = ("bowl", "bottle", "vase")  # bodies of revolution about z: a grasp turned about it is the same grasp
SPLIT_NAMES: tuple[str, ...] = ("train", "test", "wide-train", "wide-test")  # seed splits (app.objects.families)
