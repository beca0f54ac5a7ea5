"""Every check of gyrocal as one kind of `Finding`: the input's format and physics, the outlier
screen, the reference mounting, and the refusals before a posterior is sampled."""
