"""Time-expanded CP-SAT and CNF models of an instance (built here, solved by ``bille.solvers``)."""

SAT, UNSAT, UNKNOWN = "sat", "unsat", "unknown"  # a back end's answer for one model
