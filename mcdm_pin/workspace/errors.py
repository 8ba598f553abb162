"""The workspace's own exception type."""

from __future__ import annotations

from ..exceptions import McdmError


class WorkspaceError(McdmError, ValueError):
    """A workspace cannot be set up, run or read: an unknown coordinate, a bad range or poses file, a
    store that exists or was made with other settings, a scheduler that cannot be reached."""
