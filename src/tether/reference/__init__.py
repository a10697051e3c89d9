"""The reference pages of the documentation, generated from the code.

Every scenario key (walked from the pydantic models, the registered strategies' and
target generators' ``Params`` and the scenes' signatures), every command and option
of the typer app, every summary key and every Parquet column: each with its
description, so that the documentation cannot drift from the product. The site's build
hook (``docs/_hooks/reference.py``) writes the pages with :mod:`tether.reference.pages`.
"""
