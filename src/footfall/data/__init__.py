"""Stored data: demonstrations, their terrains and the run logs in one SQLite store.

Records: ``demonstration``, ``runlog``. The file: ``schema`` (tables, version, migrations),
``codec`` (arrays in columns), ``connection`` (transactions). Queries: ``store.DemoStore``.
"""
