"""vemwear: quasistatic frictional contact with wear by the virtual element method."""

__version__ = "0.1.0"
