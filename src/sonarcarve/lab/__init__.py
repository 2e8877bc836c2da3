"""The lab: experiments, demo, reports and figures on the simulator. Imports everything; the
product (:mod:`sonarcarve` minus :mod:`sonarcarve.sim` and this package) never imports it."""
