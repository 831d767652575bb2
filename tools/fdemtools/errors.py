"""The tools' error type, apart so that every module (common, curves) can raise it without importing the others."""


class ToolError(Exception):
    """Bad input or a state the tools cannot work with; the message is shown to the user as one line."""
