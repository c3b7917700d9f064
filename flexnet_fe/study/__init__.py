"""``flexnet study``: accuracy against cost, stability maps, simplifications and throughput
(issue 15). See :mod:`flexnet_fe.study.run` for the driver and ``docs/study/README.md`` for the
page it writes."""
