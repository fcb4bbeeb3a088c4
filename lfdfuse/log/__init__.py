"""All MCAP access of lfdfuse: messages, the writer and the reader."""

from lfdfuse.log.reader import Run, read_run
from lfdfuse.log.writer import LogWriter

__all__ = ["LogWriter", "Run", "read_run"]
