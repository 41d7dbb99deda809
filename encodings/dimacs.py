"""The time-expanded model as a DIMACS CNF file, for inspection and for other SAT solvers."""
from __future__ import annotations


def dump(model, path) -> None:
    """Write the model as DIMACS CNF for inspection: first a comment naming each variable, then
    the ``p cnf`` line and the clauses. Cardinality groups of up to six literals become
    pairwise clauses, larger ones a sequential counter (auxiliary variables after the model's
    own, named in the comments too), as the SAT back end encodes them."""
    from pysat.card import CardEnc, EncType

    top, extra, aux = model.num_vars, [], []
    for group, exactly in [(g, True) for g in model.exactly_one if g] + [(g, False) for g in model.at_most_one if g]:
        if len(group) <= 6:
            extra += [[-a, -b] for k, a in enumerate(group) for b in group[k + 1:]]
        else:
            enc = CardEnc.atmost(lits=group, bound=1, top_id=top, encoding=EncType.seqcounter)
            aux.append((top + 1, max(top, enc.nv)))
            top = max(top, enc.nv)
            extra += enc.clauses
        if exactly:
            extra.append(list(group))
    with open(path, "w") as f:
        for v in range(1, model.num_vars + 1):
            f.write(f"c {v} {model.names[v]}\n")
        for first, last in aux:
            if first <= last:
                f.write(f"c {first}-{last} at-most-one counter\n")
        f.write(f"p cnf {top} {len(model.clauses) + len(extra)}\n")
        for c in model.clauses + extra:
            f.write(" ".join(map(str, c)) + " 0\n")
