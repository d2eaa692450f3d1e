"""Reports: Markdown tables and PNG plots of the programs' results (I/O edge)."""
