"""workcell: the simulated coordination and control layers, and the command line.

So far this package holds the ``multiarm`` console command (:mod:`workcell.cli`);
the cell model, its compilation into a scheduling problem (FCL, OMPL) and the
discrete-event simulation come with later work (DESIGN.md).
"""
