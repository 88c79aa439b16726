"""Time integration: Zhai's explicit scheme (:mod:`.zhai`) and the stability limits of every model
ttbpipe integrates with it (:mod:`.limits`)."""
