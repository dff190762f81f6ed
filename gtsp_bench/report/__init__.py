"""Reports: the paper's results page, figures, plots, performance profiles and the generated
blocks of the documentation."""
