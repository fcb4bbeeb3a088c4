"""The command-line interface: the only layer that prints, exits or imports typer and rich."""
