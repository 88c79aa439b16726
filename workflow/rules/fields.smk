# Stage: random fields of track and bridge parameters (paper sec. 3.1; docs/random_fields.md).


rule sample_fields:
    """Draw the study's cross-correlated field samples (multiplicative factors per carrier)."""
    output:
        "results/fields/samples.parquet",
    params:
        fields=config.get("fields", {}),
        seed=config["study"]["seed"],
        version=MODEL_VERSION,
    log:
        "logs/fields/sample_fields.log",
    script:
        "../scripts/sample_fields.py"
