"""Reports: Markdown tables and PNG plots of the programs' results (I/O edge).

The plot files' names, shared by ``tapp process --plots``, ``tapp guide --plots`` and the
pipeline's ``DIR/plots`` (here, so that naming them does not import matplotlib).
"""

#: TAPP III: σ against time, fit beside real; the B-plane 1σ/3σ ellipses.
SIGMA_PNG = "sigma_history.png"
BPLANE_PNG = "bplane_ellipses.png"
#: TAPP III with ``[output] frames = ["inertial", "ric"]``: σ of the orbit in RIC axes
#: against time, as a plot and as a table.
RIC_PNG = "sigma_ric.png"
RIC_CSV = "sigma_ric.csv"
#: TAPP II: the final B-plane miss scatter; the ΔV histograms.
SCATTER_PNG = "bplane_scatter.png"
HISTOGRAM_PNG = "dv_histograms.png"
