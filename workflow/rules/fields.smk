# Stage: random fields of track and bridge parameters (paper sec. 3.1; docs/random_fields.md).


rule sample_fields:
    """Draw the study's cross-correlated field samples (multiplicative factors per carrier)."""
    output:
        results_path("fields/samples.parquet"),
    params:
        fields=config.get("fields", {}),
        seed=config["study"]["seed"],
        version=MODEL_VERSION,
    log:
        log_path("fields/sample_fields.log"),
    script:
        "../scripts/sample_fields.py"
