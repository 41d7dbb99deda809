"""Time-expanded CP-SAT and CNF models of an instance (built here, solved by ``bille.solvers``)."""
