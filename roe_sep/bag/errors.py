"""The one exception of the bag layer."""


class BagError(Exception):
    """A bag cannot be read or written; the message says which path and why."""
