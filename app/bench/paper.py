"""The paper's published success rates (ICRA 2023, Tables I and II), overall per category and mean,
to print beside ours. Keys: pose -> method -> {category or 'mean': overall success}."""

from app.predict.methods import canonical

TABLE_I = {
    "upright": {
        "cpd": {"mug": 0.47, "bowl": 0.80, "bottle": 0.54, "mean": 0.60},
        "bps-ndf": {"mug": 0.89, "bowl": 0.81, "bottle": 0.85, "mean": 0.85},
        "bps-scf": {"mug": 0.65, "bowl": 0.69, "bottle": 0.39, "mean": 0.58},
        "bps-nif": {"mug": 0.99, "bowl": 0.98, "bottle": 0.68, "mean": 0.88},
        "ibs-ndf": {"mug": 0.84, "bowl": 0.97, "bottle": 0.93, "mean": 0.91},
        "ibs-scf": {"mug": 0.53, "bowl": 0.34, "bottle": 0.45, "mean": 0.44},
        "ibs-nif": {"mug": 0.99, "bowl": 0.96, "bottle": 0.90, "mean": 0.95},
    },
    "arbitrary": {
        "cpd": {"mug": 0.11, "bowl": 0.43, "bottle": 0.41, "mean": 0.32},
        "bps-ndf": {"mug": 0.47, "bowl": 0.58, "bottle": 0.55, "mean": 0.53},
        "bps-scf": {"mug": 0.43, "bowl": 0.51, "bottle": 0.41, "mean": 0.45},
        "bps-nif": {"mug": 0.65, "bowl": 0.67, "bottle": 0.45, "mean": 0.59},
        "ibs-ndf": {"mug": 0.39, "bowl": 0.71, "bottle": 0.53, "mean": 0.54},
        "ibs-scf": {"mug": 0.44, "bowl": 0.31, "bottle": 0.36, "mean": 0.37},
        "ibs-nif": {"mug": 0.74, "bowl": 0.75, "bottle": 0.59, "mean": 0.69},
    },
}

# Table II (out of domain), overall; the paper's "NDF" row is BPS+NDF and "Ours" is IBS+NIF.
TABLE_II = {
    "upright": {"cpd": {"bowl-demos-on-mug": 0.78, "bottle-demos-on-vase": 0.50},
                "bps-ndf": {"bowl-demos-on-mug": 0.62, "bottle-demos-on-vase": 0.66},
                "ibs-nif": {"bowl-demos-on-mug": 0.99, "bottle-demos-on-vase": 0.92}},
    "arbitrary": {"cpd": {"bowl-demos-on-mug": 0.53, "bottle-demos-on-vase": 0.30},
                  "bps-ndf": {"bowl-demos-on-mug": 0.51, "bottle-demos-on-vase": 0.35},
                  "ibs-nif": {"bowl-demos-on-mug": 0.73, "bottle-demos-on-vase": 0.56}},
}


def paper_overall(pose: str, method: str, column: str) -> float | None:
    """The paper's overall success for a pose, method ('nift' = 'ibs-nif') and task or 'mean'."""
    method = canonical(method)
    for table in (TABLE_I, TABLE_II):
        value = table.get(pose, {}).get(method, {}).get(column)
        if value is not None:
            return value
    return None

# Table III (SCF order n of the NIF), IBS+NIF mean overall success.
TABLE_III = {"upright": {1: 0.92, 3: 0.95, 5: 0.95, 7: 0.94, 10: 0.93},
             "arbitrary": {1: 0.54, 3: 0.65, 5: 0.69, 7: 0.66, 10: 0.62}}
