"""What the tests share: every module used by more than one test file
(docs/testing.md, "Test helpers"), imported as ``helpers.NAME`` (``from
helpers.cli import softplc``). The tests directory is on ``sys.path`` (pytest
puts a test file's directory there), so this package is found as
``helpers``; a module here imports its siblings the same way."""
