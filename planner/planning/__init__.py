"""Planning: which path to touch along next (DESIGN §4.10-4.12, §4.15): candidates, their cast
outcomes, survivor sets, scores, the search, the strategies, the forecast and the plan."""
