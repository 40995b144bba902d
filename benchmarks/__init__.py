"""Side-by-side benchmarks of mgn against the libraries users would otherwise call.

Run `python -m benchmarks [--quick]` from the repository root; see benchmarks/README.md. Not part
of the test suite.
"""
