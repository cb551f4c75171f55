within StockbridgeDamper.Sources;
model Position "Motion source: the flange follows the input position s (its time derivative must be known to the model: see the __pyfit(inputDerivatives) annotation of the exported model)"
  input Real s(unit="m") "Prescribed flange position";
  Interfaces.Flange flange "Flange moved by the source; -flange.f is the force the source applies";
  Real F(unit="N") "Force the source applies to the flange, positive in +s direction";
equation
  flange.s = s;
  F = -flange.f;
end Position;
