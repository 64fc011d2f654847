"""Recognition: contacts in, weighted hypotheses out (DESIGN §4.2-4.7): constraint tables, the
interpretation tree, pose fit and bounds, model and free-space checks, weights, the session."""
