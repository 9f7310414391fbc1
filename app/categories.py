"""The object category names, importable without the mesh libraries (the CLI's parser needs them)."""

CATEGORIES: tuple[str, ...] = ("mug", "bowl", "bottle", "vase")
IN_DOMAIN: tuple[str, ...] = ("mug", "bowl", "bottle")  # vases stay out of training data
