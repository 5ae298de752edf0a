"""What the tests share: helpers imported by many test files (``from
helpers.cli import softplc``). The tests directory is on ``sys.path`` (pytest
puts a test file's directory there), so this package is found as ``helpers``."""
