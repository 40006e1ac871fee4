"""Stored data: demonstrations and run logs in one SQLite store."""
