"""The adversarial suite (issue 13): generated hostile inputs against the whole CLI."""
