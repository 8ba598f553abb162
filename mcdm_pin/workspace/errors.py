"""The workspace's own exception types."""

from __future__ import annotations

from pathlib import Path

from ..exceptions import McdmError


class WorkspaceError(McdmError, ValueError):
    """A workspace cannot be set up, run or read: an unknown coordinate, a bad range or poses file, a
    store that exists or was made with other settings, a scheduler that cannot be reached."""


class WorkspaceInterrupted(KeyboardInterrupt):
    """Ctrl-C during a run; the message says what the store keeps (``path``, ``done``, ``chunks``)."""

    def __init__(self, path: Path, done: int, chunks: int):
        self.path, self.done, self.chunks = path, done, chunks
        if done < 0:
            what = f"{path} was not created"
        else:
            what = (f"{path} keeps {done} of {chunks} chunks"
                    + ("; give --resume to complete it" if done < chunks else ""))
        super().__init__(f"workspace interrupted: {what}")
