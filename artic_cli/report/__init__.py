"""``reports/paper.md``'s sections: each a function of the data folder that returns its rows (item, paper, ours,
verdict) and its prose and pictures; :mod:`artic_cli.stages.report` puts them together."""
