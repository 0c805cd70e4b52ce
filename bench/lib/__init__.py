"""What the studies in bench/ share (issue 44, "bench/ as a library"): provenance so far."""
