"""What the tests share: the independent referees (a brute-force simulator, 50-digit closed
forms, global searches, the sources' reference values), design generators, assertions, the
real server, and the toy types with the checks library/test_seventh_type.py runs on them in a
process of their own."""
