"""Benchmarks: the service under load (``load.py``) and the synthesis against its peers
(``python -m benchmarks.synthesis``)."""
