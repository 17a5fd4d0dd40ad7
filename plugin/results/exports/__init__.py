"""A run's results in the formats other tools read: Parquet and CSV tables (``tables``), VTK series for
ParaView (``vtk``) and LAMMPS-style dumps for OVITO (``dump``)."""
