"""Linear algebra of the core: dense or sparse bordered solves and the work ledger (solves.py),
SuperLU orderings kept per pattern (orderings.py), compiled triangular substitution
(triangular.py), periodic block-tridiagonal matrices and their shifted solves
(block_tridiagonal.py)."""
