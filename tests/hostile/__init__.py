"""The adversarial suite: generated hostile inputs against the whole CLI."""
