"""Analysis of study results: the orthotropic hyperelastic model (paper section 4.1) and figures.
Pure numpy/scipy/matplotlib on the CSV written by pyscripts/run_states.py."""
