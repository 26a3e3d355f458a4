"""The compiled engine (issue 21): C sources in ``src/``, the extension module `rocking_model._engine`.

See ``DESIGN.md`` in this folder for the architecture, the C API and the task list of each part."""
