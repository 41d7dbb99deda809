"""The paper's heuristics: joint A*, M*, Temporal A*, task allocation and load transfer."""
