"""The package version (kept apart so that any module can read it without importing the
package's re-exports); pyproject.toml carries the same number."""

__version__ = "0.1.0"
