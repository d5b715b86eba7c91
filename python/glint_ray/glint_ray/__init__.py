"""Render glint scenes as parts on Ray and merge them bit-identically."""

from glint_ray.driver import main, split

__all__ = ["main", "split"]
