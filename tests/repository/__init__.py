"""The repository as a whole: self-contained texts and links, house rules read from the source,
the notebooks run, the benchmarks in their quick form."""
